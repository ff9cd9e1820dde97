"""The embedded sensor against a housing accelerometer: one simulated rig observed twice (the accelerometer's
transducer model and the rig's runs)."""
