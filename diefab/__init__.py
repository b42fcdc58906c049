"""diefab: design, simulate and fabricate dice with unequal face probabilities.

The core (geometry, mass, models, targets, statistics, designs, optimizer)
imports with NumPy alone; SciPy, trimesh, pybullet, manifold3d and matplotlib
are imported by the functions that need them.
"""

from diefab.core.errors import (
    DesignError,
    DiefabError,
    FabricationError,
    GeometryError,
    OutputError,
    PhysicsError,
    StatsError,
    TargetError,
)
from diefab.dice.assignment import assign_values
from diefab.dice.design import Design, design_to_toml, list_templates, load_design, parse_design
from diefab.dice.families import GEM, Family, Parameter, families, family, gem_center_of_mass_y, gem_vertices
from diefab.dice.readings import markings, readings
from diefab.dice.targets import Target, parse_target
from diefab.geometry.polyhedron import Polyhedron, face_margins, solid_angles, up_faces
from diefab.made.mass import Fill, MassProperties, mass_properties
from diefab.models.probabilities import MODELS, face_probabilities, value_probabilities
from diefab.physics.profiles import load_profile
from diefab.physics.simulate import PhysicsSettings, RollResult, simulate
from diefab.search.synthesis import synthesize
from diefab.stats.goodness import GoodnessOfFit, goodness_of_fit, jsd, pearson_divergence, tvd

__version__ = "0.1.0"

__all__ = [
    "GEM",
    "MODELS",
    "Design",
    "DesignError",
    "DiefabError",
    "FabricationError",
    "Family",
    "Fill",
    "GeometryError",
    "GoodnessOfFit",
    "MassProperties",
    "OutputError",
    "Parameter",
    "PhysicsError",
    "PhysicsSettings",
    "Polyhedron",
    "RollResult",
    "StatsError",
    "Target",
    "TargetError",
    "assign_values",
    "design_to_toml",
    "face_margins",
    "face_probabilities",
    "families",
    "family",
    "gem_center_of_mass_y",
    "gem_vertices",
    "goodness_of_fit",
    "jsd",
    "list_templates",
    "load_design",
    "load_profile",
    "markings",
    "mass_properties",
    "parse_design",
    "parse_target",
    "pearson_divergence",
    "readings",
    "simulate",
    "solid_angles",
    "synthesize",
    "tvd",
    "up_faces",
    "value_probabilities",
]
