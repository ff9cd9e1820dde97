"""The bearing's housing: its mesh, its finite-element model (direct and reduced), the transient of the roller
loads through it, the base motion of its foot, and the checks of its mesh and time step."""
