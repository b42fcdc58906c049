"""python -m diefab: the command line."""

from .cli import main

main()
