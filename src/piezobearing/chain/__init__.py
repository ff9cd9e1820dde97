"""The workflow's chain in memory: for each rule the parameter studies run, one function returning what the rule
writes (the calibration, the bearing and housing, the signals); the stages write it, the studies call it."""
