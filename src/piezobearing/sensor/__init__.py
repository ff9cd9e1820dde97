"""The sensor: the PZT stack's materials, its calibration circuit (RC model), mesh and piezoelectric FEM."""
