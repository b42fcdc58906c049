"""Fabrication: paper nets (SVG/PDF) and printable solids (STL/3MF)."""
