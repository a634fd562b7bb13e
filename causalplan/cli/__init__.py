"""The ``causalplan`` command line: check, plan, transfer, compile, graph, objects, and more.

Built on click, and each command imports what it needs when it runs, so ``causalplan --help``
and ``causalplan plan`` start fast: the sentences are styled with click, and rich (tables,
progress bars) is loaded only by the commands that draw them. Every command keeps one table
of exit codes (`common.EXIT_CODES`): 0 done, 1 no (no plan, no transfer, beyond the limits),
2 invalid input, 3 could not decide (the planner timed out or failed).

One module per family of commands; `common` holds what they share. A new command is a
`click.command` in its family's module (or a new one), registered below by its name and
``module:attribute``; its module is imported only when the command runs (``lazy``).
"""

import click

from causalplan.cli.common import EXIT_CODES
from causalplan.cli.lazy import LazyGroup
from causalplan.version import __version__

COMMANDS = {
    "check": "models:check",
    "plan": "planning:plan",
    "transfer": "planning:transfer",
    "explain": "explaining:explain",
    "compile": "models:compile_command",
    "graph": "models:graph",
    "compare": "comparison:compare",
    "batch": "comparison:batch",
    "planners": "planning:planners",
    "serve": "serving:serve",
    "simulate": "simulation:simulate",
    "check-trajectory": "simulation:check_trajectory",
    "estimate-fits": "fits:estimate_fits_command",
    "objects": "models:objects",
    "analyze": "studies:analyze",
    "consensus": "crowd:consensus",
    "population": "crowd:population",
    "crowd-curve": "crowd:crowd_curve",
    "synthetic-study": "synthetic:synthetic_study",
    "export-rddl": "exports:export_rddl_command",
    "troubleshoot": "troubleshooting:troubleshoot",
}
"""Every command: its name, and where it lives under ``causalplan.cli``."""


@click.group(
    name="causalplan",
    cls=LazyGroup,
    lazy_commands=COMMANDS,
    context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 110, "show_default": True},
    epilog=f"{EXIT_CODES} Run `causalplan COMMAND --help` for a command's options and its exit codes.",
)
@click.version_option(__version__, "-V", "--version", prog_name="causalplan", message="%(prog)s %(version)s")
def app() -> None:
    """Teach a robot why an object works, then plan with that knowledge.

    A model file says which parts of an object carry which functions (step 1) and keyword rules
    such as 'provide electricity AND turn electricity into light CAUSES light' (step 2).
    A mapping file gives another object's parts the model's functions (step 3).

    Start with: causalplan plan examples/paper/desk_lamp.yaml
    """


def main() -> None:
    """Run the command line."""
    app(prog_name="causalplan")
