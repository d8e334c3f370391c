"""Outputs: plan exports, case files (zip, workbook), comparison tables and figures."""
