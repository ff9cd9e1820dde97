"""The bearing: geometry, kinematics and the lumped-parameter model (LPM), the housing's mesh and FEM."""
