"""Model versus measurement: one engine and its subjects.

Engine (imports no subject, no physics):

==========================  ==============================================================
``subject.py``              the interface a subject supplies (Subject, Problem, Representation)
``model.py``                what the engine needs of a forward model (Model protocol)
``effect.py``               the base of every catalogue effect, and the Catalogue
``params.py``, ``units.py``  the one Param class; the registry of unit suffixes
``record.py``               the record (time, measured input) and its Segments
``noise.py``                the noise floor measured from the record, and how input noise reaches the residual
``least_squares.py``        bounded least squares with Jacobian intervals
``fit.py``                  maximum likelihood with the measured floor (errors in variables)
``residual_tests.py``       whiteness, input correlation, spectrum, time windows
``selection.py``            rank by BIC, add stepwise, drop stand-ins
``verdict.py``              explained or not, and where
``engine.py``               the run: Problem -> Diagnosis -> JSON and arrays
``report/``                 report sections as small functions
``settings.py``             the ``diagnostics`` config section
==========================  ==============================================================

Subjects: ``calibration/`` (the calibration record; the first subject).
"""
