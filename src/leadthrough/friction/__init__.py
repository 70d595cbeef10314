"""Friction: the probabilistic model, its compensation, identification and logs."""
