"""The calibration diagnosis report's figures by name, apart from the report so that the workflow reads them at
its parse without the engine (scipy, numba)."""

#: Figures of a diagnosis, in the order the report shows them (drawn by piezobearing.plotting.diagnostics).
FIGURES = ("overlay", "residuals", "spectrum", "correlations", "ranking", "ladder")
