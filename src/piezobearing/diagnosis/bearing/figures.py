"""The bearing diagnosis report's figures by name, apart from the report so that the workflow reads them at
its parse without the engine (scipy, numba)."""

#: Figures of the report, in order (drawn by piezobearing.plotting.bearing_diagnosis).
FIGURES = ("overlay", "per_passage", "synchronous_average", "envelope", "spectrum", "ranking", "ladder")
