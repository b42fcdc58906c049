"""The balance of what is made: the distribution a made die rolls, predicted and held against its target.

``diefab net`` and ``diefab stl`` make a die of a material (card with glue
tabs, a print with walls, infill and engraving) whose centre of mass is not
the one the design was fitted with.  :func:`made_balance` predicts the made
die's distribution with the fast model and compares its distance to the
target with the design's own (the same model, the design's own fill); when
making it costs more than :data:`TVD_SLACK` of TVD, :attr:`Balance.warning`
says so and names the command that designs for that material.

Examples
--------
>>> from diefab.dice.design import load_design
>>> d6 = load_design("d6")
>>> b = made_balance(d6, d6.polyhedron.centroid, "paper", "160 g/m² card", inertia=np.eye(3))
>>> round(b.predicted_tvd, 6), b.warning is None
(0.0, True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diefab.dice.design import Design, format_value
from diefab.dice.families import family
from diefab.made.mass import Fill, MassProperties
from diefab.stats.goodness import tvd

__all__ = ["TVD_SLACK", "Balance", "made_balance"]

#: How much further from the target (TVD) a made die may roll than its design before a warning.
TVD_SLACK = 0.01
#: The model every output's check uses.
MODEL = "fast"


@dataclass(frozen=True)
class Balance:
    """The made die's predicted distribution against its target and against its design.

    Attributes
    ----------
    model : str
        The landing model of every figure here.
    material : str
        ``paper`` or ``print``.
    settings : str
        The material's settings in words.
    predicted : dict value -> probability
        The made die.
    predicted_tvd : float
        Its TVD to the target.
    design_tvd : float
        The design's own TVD to the target (its own fill, same model).
    command : str
        The command that designs the die for this material.
    """

    model: str
    material: str
    settings: str
    predicted: dict[str, float]
    predicted_tvd: float
    design_tvd: float
    design_fill: str
    command: str

    @property
    def warning(self) -> str | None:
        """One line when the made die rolls more than :data:`TVD_SLACK` further from the target than its design."""
        if self.predicted_tvd <= self.design_tvd + TVD_SLACK:
            return None
        return (
            f"made of {self.settings}, this die rolls TVD {self.predicted_tvd:.3f} from its target "
            f"({self.model} model; the design, {self.design_fill}: {self.design_tvd:.3f}); "
            f"design it for the material: {self.command}"
        )

    def as_json(self) -> dict:
        return {
            "model": self.model,
            "predicted": self.predicted,
            "predicted_tvd": self.predicted_tvd,
            "design_tvd": self.design_tvd,
        }

    def summary(self) -> str:
        """Two lines: the predicted distribution and the TVDs, labelled with the model."""
        signed = min(int(k) for k in self.predicted) < 0
        values = " ".join(f"{format_value(int(k), signed)}:{p:.4f}" for k, p in self.predicted.items())
        return (
            f"as made ({self.settings}), {self.model} model: {values}\n"
            f"TVD to target {self.predicted_tvd:.4f} as made, {self.design_tvd:.4f} as designed "
            f"({self.design_fill}), {self.model} model"
        )


def made_balance(
    design: Design,
    center: np.ndarray,
    material: str,
    settings: str,
    spec: str | None = None,
    *,
    fill: Fill | None = None,
    inertia: np.ndarray | None = None,
) -> Balance:
    """Predict the die made of `material` with centre of mass `center` (model units) and compare.

    Parameters
    ----------
    design : Design
        As designed (its own fill gives the reference TVD).
    center : (3,) float
        Centre of mass of the made die, model units.
    material : {"paper", "print"}
    settings : str
        The material's settings in words (for the messages).
    spec : str, optional
        How the user named the design (template name or path), for the command.
    fill : Fill, optional
        The made die's fill (default: `material` at its default settings).
    inertia : (3, 3) float, optional
        The made die's inertia tensor about its centre of mass over its
        mass, model units² (default: the fill's, computed for `design`).
    """
    from diefab.models.probabilities import model_probabilities, to_values

    poly = design.polyhedron
    goal = design.target_distribution.aligned(design.support)
    fill = fill or Fill(material)
    if inertia is None:
        body = design.mass_properties(fill)
        inertia = body.inertia / body.mass
    made_body = MassProperties(1.0, np.asarray(center, dtype=float), np.asarray(inertia, dtype=float))
    made = to_values(design, model_probabilities(MODEL, poly, made_body, fill))
    own = to_values(design, model_probabilities(MODEL, poly, design.mass_properties(), design.fill))
    if family(design.family).free_names(design.params):
        command = f"diefab optimize {spec or design.name} --fill {material} --model simulation"
    else:  # nothing to tune on this shape: design anew for the material
        command = f"diefab design {design.target} --fill {material}"
    return Balance(
        model=MODEL,
        material=material,
        settings=settings,
        predicted={str(v): float(p) for v, p in zip(design.support, made)},
        predicted_tvd=tvd(made, goal),
        design_tvd=tvd(own, goal),
        design_fill=design.fill.describe(),
        command=command,
    )
