"""Searches: fitting a die to a target (by model or by simulation), synthesis from a target, fair and
two-class dice, and calibrating physics to real rolls."""
