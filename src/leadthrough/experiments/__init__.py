"""Experiments on the twin: thesis studies, the demo, teaching sessions and their reports."""
