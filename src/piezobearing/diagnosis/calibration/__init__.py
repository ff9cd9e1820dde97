"""The calibration record as a diagnosis subject: RC baseline, effect catalogue, synthesiser."""
