"""Identification of a robot's dynamics from its logs (between friction and estimation)."""
