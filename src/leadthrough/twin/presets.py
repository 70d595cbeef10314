"""The plant the experiments, the demo, teaching and the acceptance tests run on."""

from __future__ import annotations

from leadthrough.twin.model_error import ModelError
from leadthrough.twin.simulator import TwinConfig

#: The realistic twin: link masses ±5 %, centres of mass ±5 mm, seed 1. Friction is the
#: description's: the controllers use friction identified on this same twin. Scenarios and
#: experiments that need more (friction ±20 %, a payload) state it on top of this one.
REALISTIC_TWIN = TwinConfig(model_error=ModelError(mass_error=0.05, com_error=0.005), seed=1)
