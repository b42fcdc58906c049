"""python -m diefab: the command line."""

from diefab.cli import main

main()
