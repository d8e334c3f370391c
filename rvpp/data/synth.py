"""Seeded synthetic hourly history for the RVPP case study.

The real plant, demand and market records behind the case study are not
public, so this module generates a realistic stand-in: one hourly series per
price, plant and demand, from which the optimisation model derives its
forecast bands.  Every value is a deterministic function of the seed.

Each physical component (weather, wind, each cloud field, each demand,
prices) draws from its own random stream, keyed by the component name, so
adding or changing one component leaves the others untouched.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pvlib
from scipy import signal, stats
from scipy.special import expit, ndtr, ndtri
from .files import replacing

DEFAULT_SEED = 20250318


@dataclass(frozen=True)
class Site:
    """Geographic location shared by the plants of the RVPP."""

    name: str
    latitude: float    # [deg N]
    longitude: float   # [deg E]
    altitude_m: float  # [m]
    timezone: str = "Europe/Madrid"


SITE = Site(name="Guadix plateau (Andasol area), Granada, Spain",
            latitude=37.23, longitude=-3.07, altitude_m=1100.0)

PRICE_COLUMNS = ("price_da", "price_sr_up", "price_sr_dn")
WIND_COLUMNS = ("WF1", "WF2")
PV_COLUMNS = ("PV1", "PV2", "PV3")
CSP_COLUMNS = ("CSP1",)
ED_COLUMNS = ("ED_industry", "ED_service", "ED_residential")
TD_COLUMNS = ("TD_industry", "TD_residential")
COLUMNS = (PRICE_COLUMNS + WIND_COLUMNS + PV_COLUMNS + CSP_COLUMNS
           + ED_COLUMNS + TD_COLUMNS)

# --- time ------------------------------------------------------------------

HOURS_PER_DAY = 24
DAYS_PER_YEAR = 365.25
DEGREES_PER_HOUR = 15.0  # [deg/h] Earth rotation
HALF_HOUR = pd.Timedelta(minutes=30)  # hour-beginning stamps; physics at mid-hour
W_PER_MW = 1e6

# Demand levels are calibrated on the 30 days before the default delivery day.
CALIBRATION_DAY = "2025-03-18"
CALIBRATION_WINDOW_DAYS = 30

# --- ambient temperature (Guadix, ~1,100 m) ---------------------------------

TEMP_ANNUAL_MEAN = 14.5         # [C]
TEMP_SEASONAL_AMPLITUDE = 9.5   # [K] half the Jul-Jan difference of means
TEMP_COLDEST_DAY = 15           # [day of year]
TEMP_DIURNAL_AMPLITUDE = 7.5    # [K] half the clear-day max-min range
TEMP_WARMEST_SOLAR_HOUR = 15.0  # [h]
TEMP_CLOUD_DAMPING = 0.6        # [-] diurnal range lost under full overcast
TEMP_ANOMALY_SD = 2.0           # [K]
TEMP_ANOMALY_PERSISTENCE = 48.0  # [h] e-folding time

# --- clear sky and clouds -------------------------------------------------
# Daily regime: a latent AR(1) Gaussian z; a day is clear when z is below the
# threshold that gives the month's clear-day probability, and fully overcast
# when z exceeds it by CLOUD_SPAN.

CLOUD_DAY_AUTOCORRELATION = 0.7  # [-] lag-1 day
CLEAR_DAY_PROBABILITY = (0.45, 0.48, 0.45, 0.48, 0.62, 0.82,
                         0.92, 0.86, 0.68, 0.50, 0.45, 0.42)  # [-] mid-month
CLOUD_SPAN = 1.4                 # [-] latent units from clear to overcast
CLOUD_HOUR_PERSISTENCE = 3.0     # [h] e-folding time of intra-day cloud noise
CLOUD_HOUR_SD_CLEAR = 0.04       # [-] opacity noise on clear/overcast days
CLOUD_HOUR_SD_BROKEN = 0.35      # [-] extra opacity noise on broken-cloud days
CLOUD_SHARED_VARIANCE = 0.6      # [-] share of intra-day noise common to plants
KC_OVERCAST = 0.25               # [-] GHI clear-sky index at full opacity
GHI_CLOUD_EXPONENT = 3.4         # [-] Kasten-Czeplak: kc = 1 - 0.75 * opacity ** 3.4
BEAM_CLOUD_EXPONENT = 2.6        # [-] DNI index = (1 - opacity) ** exponent
GROUND_ALBEDO = 0.2              # [-]
TURBIDITY_EXCESS_MEAN = 0.6      # [-] mean daily Linke excess over pvlib's climatology
TURBIDITY_EXCESS_SHAPE = 2.0     # [-] gamma shape of the excess
TURBIDITY_DAY_AUTOCORRELATION = 0.6  # [-] lag-1 day

# --- PV --------------------------------------------------------------------


@dataclass(frozen=True)
class PVPlant:
    """Orientation of a PV plant; tracking plants use a N-S horizontal axis."""

    name: str
    surface_tilt: float     # [deg]
    surface_azimuth: float  # [deg] clockwise from north
    tracking: bool


PV_PLANTS = (
    PVPlant("PV1", surface_tilt=30.0, surface_azimuth=180.0, tracking=False),
    PVPlant("PV2", surface_tilt=0.0, surface_azimuth=180.0, tracking=True),
    PVPlant("PV3", surface_tilt=20.0, surface_azimuth=225.0, tracking=False),
)
PV_AC_CAPACITY = 50.0          # [MW]
PV_DC_AC_RATIO = 1.2           # [-]
PV_GAMMA_PDC = -0.0035         # [1/K] power temperature coefficient
PV_INVERTER_EFFICIENCY = 0.98  # [-] nominal
TRACKER_MAX_ANGLE = 55.0       # [deg]
TRACKER_GCR = 0.35             # [-] ground coverage ratio, with backtracking
PV_LOSSES_PERCENT = dict(soiling=2, shading=1, mismatch=1.5, wiring=1.5,
                         connections=0.5, lid=1, availability=1)
MODULE_WIND_FACTOR = 0.5       # [-] module-height / hub-height wind speed

# --- CSP solar field (parabolic trough, N-S axis, E-W tracking) -------------

CSP_APERTURE = 615_000.0        # [m2] about 1.2 x Andasol-1 (510,120 m2)
CSP_PEAK_OPTICAL_EFFICIENCY = 0.73  # [-] at normal incidence, incl. mirror cleanliness
TROUGH_IAM_F1 = 0.0327          # [1/rad] EuroTrough-class IAM coefficients
TROUGH_IAM_F2 = -0.1351         # [1/rad2]
TROUGH_ROW_PITCH_RATIO = 3.0    # [-] row pitch / aperture width (17.2 m / 5.77 m)
CSP_HTF_MEAN_TEMPERATURE = 343.0  # [C] mean of 293 C inlet and 393 C outlet
CSP_HEAT_LOSS_COEFFICIENT = 0.14  # [W/(m2 K)] receivers and piping, per aperture
CSP_FIELD_AVAILABILITY = 0.99   # [-]
CSP_MAX_THERMAL = 300.0         # [MW_th] defocusing limit
GRAZING_INCIDENCE = 89.0        # [deg] largest AOI used in the IAM formula

# --- wind ------------------------------------------------------------------

WIND_FARM_CAPACITY = 50.0       # [MW]
WIND_TURBINES = 20              # 2.5 MW each
WIND_WEIBULL_SHAPE = 2.2        # [-]
WIND_WEIBULL_SCALE = 7.8        # [m/s] annual Weibull scale at 100 m hub height
WIND_SEASONAL_AMPLITUDE = 0.12  # [-] relative, windier in winter/spring
WINDIEST_DAY = 60               # [day of year]
WIND_DIURNAL_AMPLITUDE = 0.06   # [-] relative
WINDIEST_SOLAR_HOUR = 16.0      # [h]
WIND_SYNOPTIC_PERSISTENCE = 36.0  # [h] e-folding time
WIND_SYNOPTIC_VARIANCE = 0.8      # [-] share of the latent variance
WIND_GUST_PERSISTENCE = 4.0       # [h] e-folding time
WIND_SYNOPTIC_CORRELATION = 0.9   # [-] between the farms
WIND_GUST_CORRELATION = 0.3       # [-] between the farms
CUT_IN_SPEED = 3.0              # [m/s]
RATED_SPEED = 12.0              # [m/s]
CUT_OUT_SPEED = 25.0            # [m/s]
FARM_SPEED_SPREAD = 0.8         # [m/s] spread of speeds across the turbines
FARM_SPREAD_NODES = 9           # Gauss-Hermite nodes averaging over that spread
WAKE_SPEED_DEFICIT = 0.04       # [-]
TURBINE_OUTAGE_PROBABILITY = 0.02  # [-] per turbine and day

# --- demands ---------------------------------------------------------------


@dataclass(frozen=True)
class FlexibleDemand:
    """Contract limits of a flexible demand [MWh/day, MW]."""

    min_energy: float
    p_min: float
    p_max: float


DEMANDS = {
    "ED_industry": FlexibleDemand(min_energy=600.0, p_min=2.0, p_max=70.0),
    "ED_service": FlexibleDemand(min_energy=800.0, p_min=10.0, p_max=80.0),
    "ED_residential": FlexibleDemand(min_energy=600.0, p_min=5.0, p_max=60.0),
    "TD_industry": FlexibleDemand(min_energy=700.0, p_min=10.0, p_max=80.0),
    "TD_residential": FlexibleDemand(min_energy=700.0, p_min=5.0, p_max=70.0),
}
MEDIAN_DAY_ENERGY_RATIO = 1.05  # [-] median-day energy / minimum energy
DEMAND_FLOOR_FACTOR = 1.2       # [-] hourly values stay above 1.2 * p_min
DEMAND_CEILING_FACTOR = 0.9     # [-] and below 0.9 * p_max
DEMAND_SOFT_MARGIN = 0.1        # [-] share of the range softly compressed
DEMAND_SLOW_PERSISTENCE = 36.0  # [h] e-folding time of day-to-day noise
DEMAND_FAST_PERSISTENCE = 3.0   # [h] e-folding time of hour-to-hour noise
SHAPE_RAMP = 0.6                # [h] ramp time of shift and office windows

INDUSTRY_NIGHT_SHARE = 0.5      # [-] night-shift load / day-shift load
INDUSTRY_SHIFTS = (6.0, 22.0)   # [h] two day shifts
INDUSTRY_WEEKEND = (0.8, 0.5)   # [-] day-shift activity Saturday, Sunday
INDUSTRY_NOISE_SD = (0.03, 0.02)  # [-] slow, fast

SERVICE_BASE_SHARE = 0.4        # [-] night load / office-hours load
SERVICE_HOURS = (8.0, 20.0)     # [h]
SERVICE_LUNCH = (14.5, 1.0, 0.1)  # [h, h, -] centre, width, depth
SERVICE_WEEKEND = (0.8, 0.45)   # [-] office activity Saturday, Sunday
SERVICE_HVAC = (0.012, 0.03)    # [1/K] per heating, cooling degree
SERVICE_NOISE_SD = (0.03, 0.015)  # [-] slow, fast

RESIDENTIAL_BASE_SHARE = 0.5            # [-] night load / average peak-free load
RESIDENTIAL_MORNING = (8.0, 1.2, 0.35)  # [h, h, -] centre, width, height
RESIDENTIAL_WEEKEND_MORNING = 10.0      # [h] later wake-up at weekends
RESIDENTIAL_LUNCH = (14.5, 1.5, 0.2)    # [h, h, -]
RESIDENTIAL_EVENING = (21.0, 1.8, 0.7)  # [h, h, -]
RESIDENTIAL_WEEKEND = (1.0, 1.02)       # [-] daily level Saturday, Sunday
RESIDENTIAL_HVAC = (0.03, 0.03)         # [1/K]
RESIDENTIAL_NOISE_SD = (0.06, 0.03)     # [-] slow, fast

HEATING_BASE_TEMPERATURE = 15.0  # [C] electric heating below
COOLING_BASE_TEMPERATURE = 22.0  # [C] air conditioning above

PROCESS_HEAT_NIGHT_SHARE = 0.6   # [-] night heat / working-hours heat
PROCESS_HEAT_WEEKEND = (0.7, 0.55)  # [-] working-hours activity Saturday, Sunday
PROCESS_HEAT_WINTER = 0.05       # [-] extra heat at the coldest time of year
PROCESS_HEAT_NOISE_SD = (0.035, 0.015)  # [-] slow, fast

DISTRICT_HEAT_BASE_TEMPERATURE = 17.0  # [C] space heating below
DISTRICT_HEAT_REFERENCE_HDD = 9.5      # [K] mean heating degrees, mid-Feb to mid-Mar
DISTRICT_HEAT_SMOOTHING = 24.0         # [h] building thermal inertia
NETWORK_LOSS_SHARE = 0.15              # [-] of the March daily heat
HOT_WATER_SHARE = 0.45                 # [-] of the March daily heat
HOT_WATER_WINTER = 0.15                # [-] extra hot-water heat in January
HOT_WATER_PEAKS = ((7.5, 1.5, 0.8), (13.5, 1.5, 0.3), (20.5, 2.0, 0.7))  # [h, h, -]
HOT_WATER_BASE = 0.35                  # [-] relative to the peak heights
SPACE_HEAT_PEAKS = ((7.0, 2.0, 0.6), (19.5, 2.5, 0.6))  # [h, h, -]
SPACE_HEAT_BASE = 0.5                  # [-] relative to the peak heights
DISTRICT_HEAT_NOISE_SD = (0.07, 0.03)  # [-] slow, fast

# --- prices ----------------------------------------------------------------

# Mid-month reference DAM level before daily-shape and renewable effects,
# shaped after recent Iberian years: gas-set winters, wet and sunny springs.
PRICE_MONTHLY_LEVEL = (100.0, 95.0, 78.0, 62.0, 62.0, 75.0,
                       85.0, 82.0, 82.0, 86.0, 92.0, 100.0)  # [EUR/MWh]
PRICE_MORNING_PEAK = (8.5, 1.5, 0.12)   # [h, h, -] centre, width, height
PRICE_EVENING_PEAK = (21.0, 1.6, 0.30)  # [h, h, -]
PRICE_NIGHT_TROUGH = (4.0, 2.0, 0.08)   # [h, h, -] depth
PRICE_WEEKEND = (0.94, 0.88)            # [-] Saturday, Sunday
REFERENCE_IRRADIANCE = 1000.0           # [W/m2] normalises the regional solar index
PRICE_SOLAR_SENSITIVITY = 0.40          # [-] per unit regional solar index
PRICE_WIND_SENSITIVITY = 0.40           # [-] per unit wind capacity factor
PRICE_REGIME_SD = 0.14                  # [-] log-price, slow component
PRICE_REGIME_PERSISTENCE = 96.0         # [h]
PRICE_HOURLY_SD = 0.07                  # [-] log-price, fast component
PRICE_HOURLY_PERSISTENCE = 4.0          # [h]
PRICE_DA_BOUNDS = (35.0, 167.0)         # [EUR/MWh]
PRICE_SOFT_MARGIN = 10.0                # [EUR/MWh]

SR_UP_BASE = 7.0                        # [EUR/MW]
SR_UP_PER_DA = 0.10                     # [EUR/MW per EUR/MWh]
SR_UP_EVENING = (20.5, 2.0, 4.0)        # [h, h, EUR/MW] scarcity premium
SR_UP_NOISE = (0.18, 12.0)              # [-, h] log sd, persistence
SR_UP_BOUNDS = (6.0, 29.0)              # [EUR/MW]
SR_DN_BASE = 2.0                        # [EUR/MW]
SR_DN_PER_DA = 0.06                     # [EUR/MW per EUR/MWh]
SR_DN_SOLAR = 4.0                       # [EUR/MW] per unit regional solar index
SR_DN_EVENING = (21.0, 2.0, 1.5)        # [h, h, EUR/MW]
SR_DN_NOISE = (0.25, 12.0)              # [-, h]
SR_DN_BOUNDS = (1.0, 22.0)              # [EUR/MW]
SR_SOFT_MARGIN = 2.0                    # [EUR/MW]


# === random streams and generic processes ==================================

def component_rng(seed, name):
    """Random generator of one component, independent of all the others."""
    key = zlib.crc32(name.encode("utf-8"))
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(key,)))


def ar1(rng, n, persistence):
    """Stationary AR(1) series of unit variance with e-folding time `persistence` [steps]."""
    phi = np.exp(-1.0 / persistence)
    scale = np.sqrt(1.0 - phi**2)
    innovations = rng.standard_normal(n)
    innovations[0] /= scale
    return signal.lfilter([scale], [1.0, -phi], innovations)


def soft_clip(x, lower, upper, margin):
    """Identity inside the bounds less `margin`, exponential approach to the bounds outside."""
    low_knee, high_knee = lower + margin, upper - margin
    below = lower + margin * np.exp(np.minimum(x - low_knee, 0.0) / margin)
    above = upper - margin * np.exp(np.minimum(high_knee - x, 0.0) / margin)
    return np.where(x < low_knee, below, np.where(x > high_knee, above, x))


def bump(hour, centre, width):
    """Gaussian bump on the 24 h clock, 1 at `centre` [-]."""
    distance = (hour - centre + HOURS_PER_DAY / 2) % HOURS_PER_DAY - HOURS_PER_DAY / 2
    return np.exp(-0.5 * (distance / width) ** 2)


def window(hour, start, stop, ramp=SHAPE_RAMP):
    """Smooth 0-1-0 window between clock hours `start` and `stop` [-]."""
    return expit((hour - start) / ramp) * expit((stop - hour) / ramp)


def annual_cycle(day_of_year, peak_day):
    """Cosine of the season, 1 at `peak_day` and -1 half a year later [-]."""
    return np.cos(2 * np.pi * (day_of_year - peak_day) / DAYS_PER_YEAR)


def monthly_climatology(day_of_year, monthly_values):
    """Periodic linear interpolation of mid-month values to `day_of_year`."""
    mid_month = (np.arange(12) + 0.5) * DAYS_PER_YEAR / 12
    return np.interp(day_of_year, mid_month, monthly_values, period=DAYS_PER_YEAR)


def by_weekday(weekday, saturday, sunday, weekday_value=1.0):
    """Day-type factor: `weekday_value` Monday-Friday [-]."""
    return np.select([weekday == 5, weekday == 6], [saturday, sunday], weekday_value)


# === calendar ===============================================================

@dataclass(frozen=True)
class Calendar:
    """Local-time descriptors of each hour-beginning timestamp."""

    times: pd.DatetimeIndex
    hour: np.ndarray         # [h] local clock time at the middle of the hour
    day_of_year: np.ndarray  # [d] fractional, at the middle of the hour
    weekday: np.ndarray      # 0 = Monday
    day: np.ndarray          # index of the local calendar day
    solar_hour: np.ndarray   # [h] local mean solar time at the middle of the hour

    @property
    def n_days(self):
        """Number of local calendar days covered."""
        return int(self.day.max()) + 1


def hourly_index(start, end, timezone=SITE.timezone):
    """Hour-beginning local timestamps from `start` 00:00 to `end` 00:00, exclusive."""
    first = pd.Timestamp(start).tz_localize(timezone)
    last = pd.Timestamp(end).tz_localize(timezone)
    return pd.date_range(first, last, freq="h", inclusive="left", name="timestamp")


def make_calendar(times, longitude=SITE.longitude):
    """Calendar descriptors of `times`."""
    mid = times + HALF_HOUR
    hour = (mid.hour + mid.minute / 60.0).to_numpy(dtype=float)
    utc = mid.tz_convert("UTC")
    utc_hour = (utc.hour + utc.minute / 60.0).to_numpy(dtype=float)
    day, _ = pd.factorize(times.normalize())
    return Calendar(
        times=times,
        hour=hour,
        day_of_year=times.day_of_year.to_numpy(dtype=float) + hour / HOURS_PER_DAY,
        weekday=times.day_of_week.to_numpy(),
        day=day,
        solar_hour=(utc_hour + longitude / DEGREES_PER_HOUR) % HOURS_PER_DAY,
    )


def calibration_calendar(day=CALIBRATION_DAY, days=CALIBRATION_WINDOW_DAYS):
    """Calendar of the `days` local days before the delivery `day`."""
    end = pd.Timestamp(day)
    return make_calendar(hourly_index(end - pd.Timedelta(days=days), end))


# === weather ================================================================

def site_location(site=SITE):
    """pvlib Location of the site."""
    return pvlib.location.Location(site.latitude, site.longitude, site.timezone,
                                   site.altitude_m, name=site.name)


def solar_position(times, site=SITE):
    """pvlib solar position at the middle of each hour [deg]."""
    return site_location(site).get_solarposition(times + HALF_HOUR)


def linke_turbidity(cal, rng, site=SITE):
    """pvlib's monthly Linke turbidity climatology plus a persistent daily haze excess [-]."""
    climatology = pvlib.clearsky.lookup_linke_turbidity(
        cal.times + HALF_HOUR, site.latitude, site.longitude)
    latent = ar1(rng, cal.n_days, -1.0 / np.log(TURBIDITY_DAY_AUTOCORRELATION))
    excess = stats.gamma.ppf(ndtr(latent), TURBIDITY_EXCESS_SHAPE,
                             scale=TURBIDITY_EXCESS_MEAN / TURBIDITY_EXCESS_SHAPE)
    return climatology.to_numpy() + excess[cal.day]


def clear_sky(times, solpos, turbidity, site=SITE):
    """Ineichen clear-sky GHI, DNI, DHI [W/m2]."""
    sky = site_location(site).get_clearsky(times + HALF_HOUR, model="ineichen",
                                           solar_position=solpos,
                                           linke_turbidity=turbidity)
    sky.index = times
    return sky


def climatological_temperature(cal):
    """Seasonal and clear-day diurnal mean air temperature [C]."""
    seasonal = TEMP_ANNUAL_MEAN - TEMP_SEASONAL_AMPLITUDE * annual_cycle(
        cal.day_of_year, TEMP_COLDEST_DAY)
    return seasonal, TEMP_DIURNAL_AMPLITUDE * np.cos(
        2 * np.pi * (cal.solar_hour - TEMP_WARMEST_SOLAR_HOUR) / HOURS_PER_DAY)


def air_temperature(cal, day_opacity, rng):
    """Air temperature with cloud-damped diurnal cycle and persistent anomalies [C]."""
    seasonal, diurnal = climatological_temperature(cal)
    damping = 1.0 - TEMP_CLOUD_DAMPING * day_opacity[cal.day]
    anomaly = TEMP_ANOMALY_SD * ar1(rng, len(cal.times), TEMP_ANOMALY_PERSISTENCE)
    return seasonal + diurnal * damping + anomaly


def daily_cloud_opacity(cal, rng):
    """Regional cloud opacity of each day, persistent over days [-]."""
    n = cal.n_days
    latent = ar1(rng, n, -1.0 / np.log(CLOUD_DAY_AUTOCORRELATION))
    first_hour = np.unique(cal.day, return_index=True)[1]
    threshold = ndtri(monthly_climatology(cal.day_of_year[first_hour], CLEAR_DAY_PROBABILITY))
    return np.clip((latent - threshold) / CLOUD_SPAN, 0.0, 1.0)


def local_cloud_noise(shared_noise, rng):
    """Intra-day cloud noise of one plant, partly shared with the region [-]."""
    local = ar1(rng, len(shared_noise), CLOUD_HOUR_PERSISTENCE)
    return (np.sqrt(CLOUD_SHARED_VARIANCE) * shared_noise
            + np.sqrt(1.0 - CLOUD_SHARED_VARIANCE) * local)


def hourly_cloud_opacity(cal, day_opacity, noise):
    """Hourly opacity: daily regime plus intra-day noise, largest on broken-cloud days [-]."""
    regime = day_opacity[cal.day]
    sd = CLOUD_HOUR_SD_CLEAR + CLOUD_HOUR_SD_BROKEN * np.sin(np.pi * regime)
    return np.clip(regime + sd * noise, 0.0, 1.0)


def all_sky_irradiance(sky, opacity):
    """GHI, DNI, DHI under clouds: DNI falls faster than GHI with opacity [W/m2]."""
    kc = 1.0 - (1.0 - KC_OVERCAST) * opacity**GHI_CLOUD_EXPONENT
    kb = (1.0 - opacity) ** BEAM_CLOUD_EXPONENT
    ghi = kc * sky["ghi"].to_numpy()
    dni = kb * sky["dni"].to_numpy()
    beam_horizontal = sky["ghi"].to_numpy() - sky["dhi"].to_numpy()
    dhi = ghi - kb * beam_horizontal
    return pd.DataFrame({"ghi": ghi, "dni": dni, "dhi": dhi}, index=sky.index)


# === PV =====================================================================

def pv_orientation(plant, solpos):
    """Surface tilt and azimuth of a PV plant, tracker angles from pvlib [deg]."""
    n = len(solpos)
    if not plant.tracking:
        return np.full(n, plant.surface_tilt), np.full(n, plant.surface_azimuth)
    tracker = pvlib.tracking.singleaxis(
        solpos["apparent_zenith"], solpos["azimuth"], axis_tilt=0.0,
        axis_azimuth=180.0, max_angle=TRACKER_MAX_ANGLE, backtrack=True,
        gcr=TRACKER_GCR)
    tilt = tracker["surface_tilt"].fillna(0.0).to_numpy()
    azimuth = tracker["surface_azimuth"].fillna(180.0).to_numpy()
    return tilt, azimuth


def pv_ac_power(plant, solpos, irradiance, temp_air, wind_speed, daylight):
    """AC output of a PV plant with DC/AC clipping, zero at night [MW]."""
    tilt, azimuth = pv_orientation(plant, solpos)
    zenith = solpos["apparent_zenith"].to_numpy()
    sun_azimuth = solpos["azimuth"].to_numpy()
    dni_extra = pvlib.irradiance.get_extra_radiation(solpos.index).to_numpy()
    poa = pvlib.irradiance.get_total_irradiance(
        tilt, azimuth, zenith, sun_azimuth,
        irradiance["dni"].to_numpy(), irradiance["ghi"].to_numpy(),
        irradiance["dhi"].to_numpy(), dni_extra=dni_extra,
        albedo=GROUND_ALBEDO, model="haydavies")
    aoi = pvlib.irradiance.aoi(tilt, azimuth, zenith, sun_azimuth)
    effective = (np.nan_to_num(poa["poa_direct"]) * pvlib.iam.physical(aoi)
                 + np.nan_to_num(poa["poa_diffuse"]))
    temp_cell = pvlib.temperature.faiman(effective, temp_air, wind_speed)
    dc_capacity = PV_AC_CAPACITY * PV_DC_AC_RATIO * W_PER_MW
    losses = pvlib.pvsystem.pvwatts_losses(**PV_LOSSES_PERCENT) / 100.0
    pdc = pvlib.pvsystem.pvwatts_dc(effective, temp_cell, dc_capacity,
                                    PV_GAMMA_PDC) * (1.0 - losses)
    pac = pvlib.inverter.pvwatts(
        np.maximum(pdc, 0.0), PV_AC_CAPACITY * W_PER_MW / PV_INVERTER_EFFICIENCY,
        eta_inv_nom=PV_INVERTER_EFFICIENCY)
    return np.where(daylight, np.asarray(pac) / W_PER_MW, 0.0)


# === CSP ====================================================================

def trough_incidence_modifier(aoi):
    """Incidence angle modifier of a parabolic trough collector [-]."""
    theta = np.radians(np.clip(aoi, 0.0, GRAZING_INCIDENCE))
    iam = 1.0 + (TROUGH_IAM_F1 * theta + TROUGH_IAM_F2 * theta**2) / np.cos(theta)
    return np.clip(iam, 0.0, 1.0)


def trough_row_shading(rotation):
    """Unshaded share of the aperture when neighbouring rows cast shadows at low sun [-]."""
    return np.clip(TROUGH_ROW_PITCH_RATIO * np.cos(np.radians(rotation)), 0.0, 1.0)


def csp_field_thermal_power(solpos, irradiance, temp_air, daylight):
    """Thermal power delivered by the trough field, defocused at the cap [MW_th]."""
    tracker = pvlib.tracking.singleaxis(
        solpos["apparent_zenith"], solpos["azimuth"], axis_tilt=0.0,
        axis_azimuth=180.0, max_angle=90.0, backtrack=False)
    aoi = tracker["aoi"].fillna(90.0).to_numpy()
    rotation = tracker["tracker_theta"].fillna(90.0).to_numpy()
    absorbed = (irradiance["dni"].to_numpy() * np.cos(np.radians(aoi))
                * trough_incidence_modifier(aoi) * trough_row_shading(rotation)
                * CSP_PEAK_OPTICAL_EFFICIENCY * CSP_FIELD_AVAILABILITY)
    heat_loss = CSP_HEAT_LOSS_COEFFICIENT * (CSP_HTF_MEAN_TEMPERATURE - temp_air)
    thermal = np.clip((absorbed - heat_loss) * CSP_APERTURE / W_PER_MW, 0.0, CSP_MAX_THERMAL)
    return np.where(daylight, thermal, 0.0)


def field_heat_from_clear_sky_index(times, kc, site=SITE):
    """Heat of the modelled trough field [MW_th, up to CSP_MAX_THERMAL] under the GHI clear-sky
    index ``kc`` of each hour-beginning local timestamp in ``times``.

    The sky is pvlib's Ineichen clear sky with its monthly Linke turbidity climatology;
    ``GHI = kc·GHI_clear`` is split into beam and diffuse by the Erbs et al. (1982)
    correlation (``pvlib.irradiance.erbs``; the beam never above the clear sky's), and the
    field's optics and heat loss are :func:`csp_field_thermal_power` at the climatological
    air temperature. The modelled weather's own link of GHI to beam
    (:func:`all_sky_irradiance`) is not inverted: it lets a few per cent less GHI remove
    most of the beam, which read backwards turns every hazy hour into an overcast one.
    """
    cal = make_calendar(times)
    solpos = solar_position(times, site)
    daylight = solpos["apparent_elevation"].to_numpy() > 0.0
    turbidity = pvlib.clearsky.lookup_linke_turbidity(times + HALF_HOUR, site.latitude, site.longitude)
    sky = clear_sky(times, solpos, turbidity.to_numpy(), site)
    ghi = np.clip(np.asarray(kc, dtype=float), 0.0, 1.0) * sky["ghi"].to_numpy()
    split = pvlib.irradiance.erbs(ghi, solpos["zenith"].to_numpy(), times + HALF_HOUR)
    dni = np.minimum(np.nan_to_num(np.asarray(split["dni"], dtype=float)), sky["dni"].to_numpy())
    irradiance = pd.DataFrame({"dni": dni}, index=times)
    seasonal, diurnal = climatological_temperature(cal)
    return csp_field_thermal_power(solpos, irradiance, seasonal + diurnal, daylight)


def clear_sky_ghi(times, site=SITE):
    """pvlib's Ineichen clear-sky GHI at the site with its monthly Linke turbidity climatology
    [W/m2], and the sun's apparent elevation [deg], at the middle of each hour of ``times``."""
    solpos = solar_position(times, site)
    turbidity = pvlib.clearsky.lookup_linke_turbidity(times + HALF_HOUR, site.latitude, site.longitude)
    sky = clear_sky(times, solpos, turbidity.to_numpy(), site)
    return sky["ghi"].to_numpy(), solpos["apparent_elevation"].to_numpy()


# === wind ===================================================================

def turbine_power_curve(speed):
    """Normalised power of one turbine: cubic from cut-in to rated [-]."""
    ramp = (speed**3 - CUT_IN_SPEED**3) / (RATED_SPEED**3 - CUT_IN_SPEED**3)
    running = (speed >= CUT_IN_SPEED) & (speed < CUT_OUT_SPEED)
    return np.where(running, np.clip(ramp, 0.0, 1.0), 0.0)


def farm_power_curve(speed):
    """Normalised farm power: turbine curve averaged over the spread of speeds [-]."""
    nodes, weights = np.polynomial.hermite_e.hermegauss(FARM_SPREAD_NODES)
    weights = weights / weights.sum()
    speeds = np.maximum(speed[:, None] * (1.0 - WAKE_SPEED_DEFICIT)
                        + FARM_SPEED_SPREAD * nodes[None, :], 0.0)
    return turbine_power_curve(speeds) @ weights


def latent_wind(cal, rng):
    """Two correlated unit-variance Gaussian wind anomalies (synoptic + gusts) [-]."""
    n = len(cal.times)
    shared_slow = ar1(rng, n, WIND_SYNOPTIC_PERSISTENCE)
    shared_fast = ar1(rng, n, WIND_GUST_PERSISTENCE)
    farms = []
    for _ in WIND_COLUMNS:
        slow = (np.sqrt(WIND_SYNOPTIC_CORRELATION) * shared_slow
                + np.sqrt(1 - WIND_SYNOPTIC_CORRELATION)
                * ar1(rng, n, WIND_SYNOPTIC_PERSISTENCE))
        fast = (np.sqrt(WIND_GUST_CORRELATION) * shared_fast
                + np.sqrt(1 - WIND_GUST_CORRELATION) * ar1(rng, n, WIND_GUST_PERSISTENCE))
        farms.append(np.sqrt(WIND_SYNOPTIC_VARIANCE) * slow
                     + np.sqrt(1 - WIND_SYNOPTIC_VARIANCE) * fast)
    return farms


def hub_wind_speed(cal, latent):
    """Hub-height wind speed with Weibull marginal, seasonal and diurnal cycles [m/s]."""
    scale = (WIND_WEIBULL_SCALE
             * (1.0 + WIND_SEASONAL_AMPLITUDE * annual_cycle(cal.day_of_year, WINDIEST_DAY))
             * (1.0 + WIND_DIURNAL_AMPLITUDE * np.cos(
                 2 * np.pi * (cal.solar_hour - WINDIEST_SOLAR_HOUR) / HOURS_PER_DAY)))
    exceedance = ndtr(-latent)
    return scale * (-np.log(exceedance)) ** (1.0 / WIND_WEIBULL_SHAPE)


def turbine_availability(cal, rng):
    """Share of turbines in service, outages lasting whole days [-]."""
    out = rng.binomial(WIND_TURBINES, TURBINE_OUTAGE_PROBABILITY, cal.n_days)
    return 1.0 - out[cal.day] / WIND_TURBINES


def wind_farm_power(cal, speed, rng):
    """Available power of a wind farm [MW]."""
    return WIND_FARM_CAPACITY * farm_power_curve(speed) * turbine_availability(cal, rng)


# === demands ================================================================

def daily_profile(hour, base, peaks):
    """Base plus Gaussian peaks given as (centre [h], width [h], height) [-]."""
    return base + sum(height * bump(hour, centre, width) for centre, width, height in peaks)


def unit_mean_profile(hour, base, peaks):
    """`daily_profile` scaled to a mean of 1 over the 24 h clock [-]."""
    clock = np.arange(HOURS_PER_DAY) + 0.5
    return daily_profile(hour, base, peaks) / daily_profile(clock, base, peaks).mean()


def degrees_below(temperature, base):
    """Heating degrees [K]."""
    return np.maximum(base - temperature, 0.0)


def degrees_above(temperature, base):
    """Cooling degrees [K]."""
    return np.maximum(temperature - base, 0.0)


def hvac_factor(temperature, per_heating_degree, per_cooling_degree):
    """Relative extra load for electric heating and air conditioning [-]."""
    return (1.0 + per_heating_degree * degrees_below(temperature, HEATING_BASE_TEMPERATURE)
            + per_cooling_degree * degrees_above(temperature, COOLING_BASE_TEMPERATURE))


def exponential_smoothing(x, time_constant):
    """First-order lag of `x` with `time_constant` [steps], started at x[0]."""
    alpha = 1.0 - np.exp(-1.0 / time_constant)
    smoothed, _ = signal.lfilter([alpha], [1.0, alpha - 1.0], x,
                                 zi=[(1.0 - alpha) * x[0]])
    return smoothed


def industry_power_shape(cal, temperature):
    """Shift-work industrial load: two day shifts on weekdays, reduced at weekends [-]."""
    activity = by_weekday(cal.weekday, *INDUSTRY_WEEKEND)
    day_shifts = window(cal.hour, *INDUSTRY_SHIFTS) * activity
    return INDUSTRY_NIGHT_SHARE + (1.0 - INDUSTRY_NIGHT_SHARE) * day_shifts


def service_power_shape(cal, temperature):
    """Commercial load: office hours with a lunch dip, HVAC-driven seasonality [-]."""
    lunch_centre, lunch_width, lunch_depth = SERVICE_LUNCH
    office = (window(cal.hour, *SERVICE_HOURS)
              * (1.0 - lunch_depth * bump(cal.hour, lunch_centre, lunch_width)))
    activity = by_weekday(cal.weekday, *SERVICE_WEEKEND)
    load = SERVICE_BASE_SHARE + (1.0 - SERVICE_BASE_SHARE) * office * activity
    return load * hvac_factor(temperature, *SERVICE_HVAC)


def residential_power_shape(cal, temperature):
    """Household load: morning and larger evening peaks, higher in winter [-]."""
    weekend = cal.weekday >= 5
    _, morning_width, morning_height = RESIDENTIAL_MORNING
    morning_centre = np.where(weekend, RESIDENTIAL_WEEKEND_MORNING, RESIDENTIAL_MORNING[0])
    load = (RESIDENTIAL_BASE_SHARE
            + morning_height * bump(cal.hour, morning_centre, morning_width)
            + daily_profile(cal.hour, 0.0, (RESIDENTIAL_LUNCH, RESIDENTIAL_EVENING)))
    return (load * by_weekday(cal.weekday, *RESIDENTIAL_WEEKEND)
            * hvac_factor(temperature, *RESIDENTIAL_HVAC))


def process_heat_shape(cal, temperature):
    """Industrial process heat: flat in working hours, lower at nights and weekends [-]."""
    activity = by_weekday(cal.weekday, *PROCESS_HEAT_WEEKEND)
    working = window(cal.hour, *INDUSTRY_SHIFTS) * activity
    winter = 1.0 + PROCESS_HEAT_WINTER * annual_cycle(cal.day_of_year, TEMP_COLDEST_DAY)
    return (PROCESS_HEAT_NIGHT_SHARE + (1.0 - PROCESS_HEAT_NIGHT_SHARE) * working) * winter


def district_heat_shape(cal, temperature):
    """Residential heat: network losses, hot water and degree-hour space heating [-]."""
    hot_water = (unit_mean_profile(cal.hour, HOT_WATER_BASE, HOT_WATER_PEAKS)
                 * (1.0 + HOT_WATER_WINTER * annual_cycle(cal.day_of_year, TEMP_COLDEST_DAY)))
    felt = exponential_smoothing(temperature, DISTRICT_HEAT_SMOOTHING)
    heating = (unit_mean_profile(cal.hour, SPACE_HEAT_BASE, SPACE_HEAT_PEAKS)
               * degrees_below(felt, DISTRICT_HEAT_BASE_TEMPERATURE)
               / DISTRICT_HEAT_REFERENCE_HDD)
    space_heat_share = 1.0 - NETWORK_LOSS_SHARE - HOT_WATER_SHARE
    return NETWORK_LOSS_SHARE + HOT_WATER_SHARE * hot_water + space_heat_share * heating


DEMAND_MODELS = {
    "ED_industry": (industry_power_shape, INDUSTRY_NOISE_SD),
    "ED_service": (service_power_shape, SERVICE_NOISE_SD),
    "ED_residential": (residential_power_shape, RESIDENTIAL_NOISE_SD),
    "TD_industry": (process_heat_shape, PROCESS_HEAT_NOISE_SD),
    "TD_residential": (district_heat_shape, DISTRICT_HEAT_NOISE_SD),
}


def demand_level(name):
    """Scale [MW] that gives the noise-free calibration window its target median-day energy."""
    shape_of, _ = DEMAND_MODELS[name]
    cal = calibration_calendar()
    seasonal, diurnal = climatological_temperature(cal)
    shape = pd.Series(shape_of(cal, seasonal + diurnal))
    median_day = shape.groupby(np.floor(cal.hour)).median().sum()
    return MEDIAN_DAY_ENERGY_RATIO * DEMANDS[name].min_energy / median_day


def demand(name, cal, temperature, rng):
    """Hourly consumption of a flexible demand with persistent noise [MW or MW_th]."""
    shape_of, (slow_sd, fast_sd) = DEMAND_MODELS[name]
    n = len(cal.times)
    noise = (1.0 + slow_sd * ar1(rng, n, DEMAND_SLOW_PERSISTENCE)
             + fast_sd * ar1(rng, n, DEMAND_FAST_PERSISTENCE))
    limits = DEMANDS[name]
    lower = DEMAND_FLOOR_FACTOR * limits.p_min
    upper = DEMAND_CEILING_FACTOR * limits.p_max
    load = demand_level(name) * shape_of(cal, temperature) * noise
    return soft_clip(load, lower, upper, DEMAND_SOFT_MARGIN * (upper - lower))


# === prices =================================================================

def price_level(cal):
    """Monthly reference day-ahead level interpolated over the year [EUR/MWh]."""
    return monthly_climatology(cal.day_of_year, PRICE_MONTHLY_LEVEL)


def day_ahead_price(cal, solar_index, wind_factor, rng):
    """Day-ahead price with daily shape, weekend discount and merit-order effect [EUR/MWh]."""
    n = len(cal.times)
    shape = (daily_profile(cal.hour, 1.0, (PRICE_MORNING_PEAK, PRICE_EVENING_PEAK))
             - PRICE_NIGHT_TROUGH[2] * bump(cal.hour, *PRICE_NIGHT_TROUGH[:2]))
    merit_order = (1.0 - PRICE_SOLAR_SENSITIVITY * solar_index
                   - PRICE_WIND_SENSITIVITY * wind_factor)
    log_noise = (PRICE_REGIME_SD * ar1(rng, n, PRICE_REGIME_PERSISTENCE)
                 + PRICE_HOURLY_SD * ar1(rng, n, PRICE_HOURLY_PERSISTENCE))
    price = (price_level(cal) * by_weekday(cal.weekday, *PRICE_WEEKEND) * shape
             * merit_order * np.exp(log_noise))
    return soft_clip(price, *PRICE_DA_BOUNDS, PRICE_SOFT_MARGIN)


def reserve_price(cal, mean, log_sd, persistence, bounds, rng):
    """Band price: mean times mean-one lognormal AR noise, softly bounded [EUR/MW]."""
    noise = np.exp(log_sd * ar1(rng, len(cal.times), persistence) - 0.5 * log_sd**2)
    return soft_clip(mean * noise, *bounds, SR_SOFT_MARGIN)


def reserve_up_price(cal, price_da, rng):
    """aFRR upward band price, tracking the DAM level and evening scarcity [EUR/MW]."""
    centre, width, premium = SR_UP_EVENING
    mean = SR_UP_BASE + SR_UP_PER_DA * price_da + premium * bump(cal.hour, centre, width)
    return reserve_price(cal, mean, *SR_UP_NOISE, SR_UP_BOUNDS, rng)


def reserve_down_price(cal, price_da, solar_index, rng):
    """aFRR downward band price, tracking the DAM level and solar hours [EUR/MW]."""
    centre, width, premium = SR_DN_EVENING
    mean = (SR_DN_BASE + SR_DN_PER_DA * price_da + SR_DN_SOLAR * solar_index
            + premium * bump(cal.hour, centre, width))
    return reserve_price(cal, mean, *SR_DN_NOISE, SR_DN_BOUNDS, rng)


# === assembly ===============================================================

def build_history(seed: int = DEFAULT_SEED, start: str = "2024-12-01",
                  end: str = "2026-01-01") -> pd.DataFrame:
    """Synthetic hourly history from local `start` 00:00 to `end` 00:00 (exclusive)."""
    times = hourly_index(start, end)
    cal = make_calendar(times)
    n = len(times)
    solpos = solar_position(times)
    daylight = solpos["apparent_elevation"].to_numpy() > 0.0
    sky = clear_sky(times, solpos,
                    linke_turbidity(cal, component_rng(seed, "weather/turbidity")))

    weather = component_rng(seed, "weather/clouds")
    day_opacity = daily_cloud_opacity(cal, weather)
    shared_clouds = ar1(weather, n, CLOUD_HOUR_PERSISTENCE)
    temperature = air_temperature(cal, day_opacity, component_rng(seed, "weather/temperature"))

    out = {}
    speeds = [hub_wind_speed(cal, latent)
              for latent in latent_wind(cal, component_rng(seed, "wind/speed"))]
    for name, speed in zip(WIND_COLUMNS, speeds):
        out[name] = wind_farm_power(cal, speed, component_rng(seed, f"wind/{name}/outages"))
    module_wind = MODULE_WIND_FACTOR * speeds[0]

    def local_irradiance(plant_name):
        noise = local_cloud_noise(shared_clouds, component_rng(seed, f"clouds/{plant_name}"))
        return all_sky_irradiance(sky, hourly_cloud_opacity(cal, day_opacity, noise))

    for plant in PV_PLANTS:
        out[plant.name] = pv_ac_power(plant, solpos, local_irradiance(plant.name),
                                      temperature, module_wind, daylight)
    out["CSP1"] = csp_field_thermal_power(solpos, local_irradiance("CSP1"),
                                          temperature, daylight)

    regional = all_sky_irradiance(sky, hourly_cloud_opacity(cal, day_opacity, shared_clouds))
    solar_index = regional["ghi"].to_numpy() / REFERENCE_IRRADIANCE
    wind_factor = sum(out[name] for name in WIND_COLUMNS) / (len(WIND_COLUMNS)
                                                             * WIND_FARM_CAPACITY)
    out["price_da"] = day_ahead_price(cal, solar_index, wind_factor,
                                      component_rng(seed, "price/da"))
    out["price_sr_up"] = reserve_up_price(cal, out["price_da"],
                                          component_rng(seed, "price/sr_up"))
    out["price_sr_dn"] = reserve_down_price(cal, out["price_da"], solar_index,
                                            component_rng(seed, "price/sr_dn"))

    for name in ED_COLUMNS + TD_COLUMNS:
        out[name] = demand(name, cal, temperature, component_rng(seed, f"demand/{name}"))

    frame = pd.DataFrame({name: np.asarray(out[name], dtype=float) for name in COLUMNS})
    frame.insert(0, "timestamp", times)
    return frame


HISTORY_HEADER = b"timestamp,"  # how a history CSV begins


def write_history(path, seed: int = DEFAULT_SEED) -> pd.DataFrame:
    """Write the default-span history as CSV and return it as written, rounded to 3 decimals.

    Timestamps are ISO 8601 local times with their UTC offset. The file is written beside
    ``path`` and renamed into place, so ``path`` is never seen half-written.
    """

    frame = build_history(seed)
    frame[list(COLUMNS)] = frame[list(COLUMNS)].round(3)
    text = frame.assign(timestamp=frame["timestamp"].map(pd.Timestamp.isoformat))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path) as temporary:
        text.to_csv(temporary, index=False)
    return frame
