"""Shipped design templates (TOML files); installed as the package ``diefab.templates``."""
