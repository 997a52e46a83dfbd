"""The documented path of :mod:`embodichain_core.sim.scene_build.articulation_loader` (scene building moved
into ``sim/scene_build/``): importing this module gives that module itself, so
attributes, monkeypatching and ``isinstance`` checks see one object."""

import sys

from embodichain_core.sim.scene_build import articulation_loader as _module

sys.modules[__name__] = _module
