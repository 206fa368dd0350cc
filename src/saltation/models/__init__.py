"""Models shipped with saltation, each a short file that reads like its source.

:data:`SHIPPED` holds those the command line names, with what it needs to know of
each (a summary, where a transient starts), declared in each model's own file
(:mod:`~saltation.models.shipped`).  The models:

- :mod:`~saltation.models.trilinear`: the trilinear spring of *Fold bifurcations in discontinuous systems*;
- :mod:`~saltation.models.block_on_belt`: the paper's block on a belt (stick-slip);
- :mod:`~saltation.models.impact_oscillator`: a forced oscillator against a rigid stop;
- :mod:`~saltation.models.symmetric_impact_oscillator`: the same between two symmetric stops;
- :mod:`~saltation.models.bouncing_ball`: a ball on a vibrating table;
- :mod:`~saltation.models.friction_oscillator`: a forced oscillator with dry friction on a belt;
- :mod:`~saltation.models.two_mass_stops`: two forced masses between compliant stops;
- :mod:`~saltation.models.chain`: a chain of masses, a scalable benchmark;
- :mod:`~saltation.models.relay_feedback`: a third-order relay feedback system;
- :mod:`~saltation.models.tilted_relay`: a forced relay oscillator with a tilted switching line;
- :mod:`~saltation.models.sliding_mode`: a planar sliding-mode control system;
- :mod:`~saltation.models.buck_converter`: the DC-DC buck converter under PWM control.
"""

from importlib import import_module

from .block_on_belt import WRegion, block_on_belt
from .bouncing_ball import bouncing_ball
from .buck_converter import buck_converter
from .chain import chain
from .friction_oscillator import friction_oscillator
from .impact_oscillator import impact_oscillator
from .relay_feedback import relay_feedback
from .shipped import ShippedModel
from .sliding_mode import sliding_mode
from .symmetric_impact_oscillator import symmetric_impact_oscillator
from .tilted_relay import tilted_relay
from .trilinear import trilinear
from .two_mass_stops import two_mass_stops

#: The models the command line names, in the order of its help: ``{name: ShippedModel}``.
#: (Each module's own SHIPPED: the modules are looked up by name, since each exports a function of its
#: own name that hides the module as an attribute of this package.)
SHIPPED: dict[str, ShippedModel] = {
    m.SHIPPED.name: m.SHIPPED
    for m in (
        import_module(f"{__name__}.{name}")
        for name in ("trilinear", "block_on_belt", "impact_oscillator", "bouncing_ball", "friction_oscillator",
                     "relay_feedback", "buck_converter", "two_mass_stops", "tilted_relay", "symmetric_impact_oscillator",
                     "sliding_mode")
    )
}

__all__ = [
    "SHIPPED", "ShippedModel",
    "WRegion", "block_on_belt", "bouncing_ball", "buck_converter", "chain", "friction_oscillator",
    "impact_oscillator", "relay_feedback", "sliding_mode", "symmetric_impact_oscillator", "tilted_relay", "trilinear",
    "two_mass_stops",
]
