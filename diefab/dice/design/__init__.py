"""Designs (:mod:`.spec`: the :class:`Design` value) and design files (:mod:`.files`: templates, TOML).

Examples
--------
>>> design = load_design("fudge-gem")
>>> design.params
{'a': 1.18, 'b': 0.52, 'c': 0.72, 'd': 1.41}
>>> design.value_of["f5"], design.label_of["f4"]
(0, '+2')
"""

from diefab.dice.design.files import (
    design_to_toml,
    files_read,
    list_templates,
    load_design,
    parse_design,
    template_for,
    template_name,
    template_path,
)
from diefab.dice.design.spec import (
    Design,
    design_axis,
    format_value,
    placed_marks,
    reference_length,
    signed_number,
)

__all__ = [
    "Design",
    "design_axis",
    "design_to_toml",
    "files_read",
    "format_value",
    "list_templates",
    "load_design",
    "parse_design",
    "placed_marks",
    "reference_length",
    "signed_number",
    "template_for",
    "template_name",
    "template_path",
]
