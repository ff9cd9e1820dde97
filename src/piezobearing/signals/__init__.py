"""The signals: noise, envelope analysis and the fault indicator."""
