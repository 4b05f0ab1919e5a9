"""Kinds picker_double_crank and picker: the seed-001 seedling picker (double crank + crank-rocker)."""
