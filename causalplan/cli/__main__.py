"""Run the command line as ``python -m causalplan.cli``."""

from causalplan.cli import main

main()
