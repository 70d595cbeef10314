"""Robot model: description, kinematic chain, Pinocchio dynamics, shipped robots."""
