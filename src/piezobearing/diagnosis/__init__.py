"""Model versus measurement: one engine and its subjects (see :mod:`piezobearing.diagnosis.subject`)."""
