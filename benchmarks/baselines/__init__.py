"""Implementations the benchmarks time the package's methods against, kept here and not in the package."""
