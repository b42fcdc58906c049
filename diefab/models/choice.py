"""Which landing model to trust for a die: the default of ``diefab predict``.

The fast model (:mod:`diefab.models.fast`) is the chain model plus corrections
learned from rigid pybullet drops under the default physics: within its
domain it is the closest to the simulator (a median TVD of about 0.02 on
gems inside the gem family's box, about 0.05 on other convex dice).  Its
domain ends where the physics is not the rigid drop it learned from: a die
whose ``[physics]`` table captures it quasi-statically (``capture_energy``
above 0, as the calibrated ``printed-table`` profile does) stops in the first
basin it reaches with little energy left, and there the quasi-static
``basins`` model is the one that follows the simulation (within 0.03-0.04 on
the shipped 4dF gems, where the fast model, learned on rigid drops, is not).

Examples
--------
>>> from diefab.dice.design import load_design
>>> best_model(load_design("fudge-gem-paper")).name
'fast'
>>> best_model(load_design("fudge-gem-print-table")).name
'basins'
"""

from __future__ import annotations

from dataclasses import dataclass

from diefab.dice.design import Design

__all__ = ["ModelChoice", "best_model"]


@dataclass(frozen=True)
class ModelChoice:
    """A landing model and why it is the one to trust.

    Attributes
    ----------
    name : str
        A key of :data:`diefab.models.MODELS`: ``"fast"`` or ``"basins"``.
    reason : str
        One clause saying why, for a report.
    """

    name: str
    reason: str


def best_model(design: Design) -> ModelChoice:
    """The landing model to trust for `design` under its own ``[physics]`` table.

    ``fast`` where the drop is the rigid one the fast model learned from,
    ``basins`` where the design's physics captures the die quasi-statically.
    """
    capture = float(design.physics.get("capture_energy", 0.0) or 0.0)
    if capture > 0:
        return ModelChoice(
            "basins",
            f"the design's physics captures the die quasi-statically (capture energy {capture:g}), outside the "
            "fast model's domain (rigid drops)",
        )
    family = "a gem inside the family box the fast model learned" if _gem_covered(design) else "a convex die"
    return ModelChoice("fast", f"{family}, rigid drops: the fast model's domain")


def _gem_covered(design: Design) -> bool:
    """Whether the gem family's learned discrepancy applies to `design` (a stable gem inside its box)."""
    from diefab.dice.families import gem_parameters
    from diefab.geometry.polyhedron import face_margins
    from diefab.models.fast import gem_discrepancy

    params = gem_parameters(design.polyhedron)
    if params is None:
        return False
    margins = face_margins(design.polyhedron, design.mass_properties().center)
    return gem_discrepancy().covers(params, margins)
