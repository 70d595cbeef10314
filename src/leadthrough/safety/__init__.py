"""Safety: limits, checks on every sample, braking and the supervisor state machine."""
