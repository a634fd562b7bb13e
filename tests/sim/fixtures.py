"""Small objects whose geometry makes a plan fail in physics, and the plans of the paper's objects."""

from __future__ import annotations

import itertools

from causalplan.objects.catalog import parse_object
from causalplan.objects.model import AssemblyObject
from causalplan.sim import StepRequest
from causalplan.troubleshoot.episode import Episode, Step

# A board with a 20 mm square hole, 30 mm deep. The thin peg (16 mm) goes in; the thick one
# (30 mm) rests on the rim, 30 mm short of its seat: a misaligned weld.
PEG_BOARD = """
id: peg_board
name: peg board
category: mechanical
goal: holding
base: board
parts:
  - id: board
    name: board
    connectors:
      - {id: hole, kind: square hole, spec: peg 20 mm, at: [0, 0, 0.01], axis: [0, 0, 1]}
    geometry:
      mass: 0.5
      shapes:
        - {shape: box, size: [0.1, 0.1, 0.01], at: [0, 0, 0.005]}
        - {shape: box, size: [0.1, 0.04, 0.03], at: [0, 0.03, 0.025]}
        - {shape: box, size: [0.1, 0.04, 0.03], at: [0, -0.03, 0.025]}
        - {shape: box, size: [0.04, 0.02, 0.03], at: [0.03, 0, 0.025]}
        - {shape: box, size: [0.04, 0.02, 0.03], at: [-0.03, 0, 0.025]}
  - id: thin_peg
    name: thin peg
    connectors:
      - {id: end, kind: square peg, spec: peg 20 mm, at: [0, 0, 0], axis: [0, 0, -1]}
    geometry:
      mass: 0.02
      shapes:
        - {shape: box, size: [0.016, 0.016, 0.05], at: [0, 0, 0.025], color: "#3366cc"}
  - id: thick_peg
    name: thick peg
    connectors:
      - {id: end, kind: square peg, spec: peg 20 mm, at: [0, 0, 0], axis: [0, 0, -1]}
    geometry:
      mass: 0.05
      shapes:
        - {shape: box, size: [0.03, 0.03, 0.05], at: [0, 0, 0.025], color: "#cc3333"}
fits:
  - {id: thin_peg_into_hole, primitive: insert, moving: thin_peg.end, fixed: board.hole}
  - {id: thick_peg_into_hole, primitive: insert, moving: thick_peg.end, fixed: board.hole}
mechanism:
  explanation: A peg holds when it sits at the bottom of the hole.
  requires:
    - {any: [thin_peg_into_hole, thick_peg_into_hole], says: a peg sits in the hole}
"""

# A heavy post with a bracket on its side. A plank placed against it (not fastened) falls;
# screwed to it, it stays.
WALL_SHELF = """
id: wall_shelf
name: wall shelf
category: mechanical
goal: storage
base: post
parts:
  - id: post
    name: post
    connectors:
      - {id: bracket, kind: bracket, spec: shelf bracket, at: [0.02, 0, 0.2], axis: [1, 0, 0]}
    geometry:
      mass: 5.0
      shapes:
        - {shape: box, size: [0.3, 0.3, 0.02], at: [0, 0, 0.01]}
        - {shape: box, size: [0.04, 0.04, 0.3], at: [0, 0, 0.17]}
  - id: plank
    name: plank
    connectors:
      - {id: edge, kind: edge, spec: shelf bracket, at: [0, 0, 0], axis: [0, 0, -1]}
    geometry:
      mass: 0.3
      shapes:
        - {shape: box, size: [0.1, 0.1, 0.02], at: [0, 0, 0.01]}
fits:
  - {id: plank_against_bracket, primitive: place, moving: plank.edge, fixed: post.bracket}
  - {id: plank_screwed_to_bracket, primitive: screw, moving: plank.edge, fixed: post.bracket}
mechanism:
  explanation: The plank holds things when it is on the bracket.
  requires:
    - {any: [plank_against_bracket, plank_screwed_to_bracket], says: the plank is on the bracket}
"""

# A lamp whose socket sits under a cap that is part of the body: on paper the bulb screws in,
# in physics it cannot get there. Same part ids and functions as a desk lamp mapping needs.
CAPPED_LAMP = """
id: capped_lamp
name: capped lamp
category: electric
goal: light
base: lamp_body
parts:
  - id: lamp_body
    name: lamp body
    connectors:
      - {id: socket, kind: threaded socket, spec: E27, at: [0, 0, 0.02], axis: [0, 0, 1]}
    geometry:
      mass: 1.0
      shapes:
        - {shape: box, size: [0.12, 0.12, 0.02], at: [0, 0, 0.01]}
        - {shape: box, size: [0.02, 0.12, 0.12], at: [-0.05, 0, 0.08]}
        - {shape: box, size: [0.12, 0.12, 0.01], at: [0, 0, 0.145]}
  - id: bulb
    name: bulb
    connectors:
      - {id: thread, kind: screw base, spec: E27, at: [0, 0, 0], axis: [0, 0, -1]}
    geometry:
      mass: 0.05
      shapes:
        - {shape: sphere, radius: 0.03, at: [0, 0, 0.03]}
fits:
  - {id: bulb_into_socket, primitive: screw, moving: bulb.thread, fixed: lamp_body.socket}
mechanism:
  explanation: The bulb lights once it is screwed into the socket.
  requires:
    - {any: [bulb_into_socket], says: the bulb is screwed into the socket}
"""

CAPPED_LAMP_MAPPING = """
object: capped_lamp
functions:
  lamp_body: [provide electricity]
  bulb: [turn electricity into light, close the circuit]
"""


def parsed_object(text: str) -> AssemblyObject:
    """Return a test object parsed from its catalog text."""
    return parse_object(text, "test_object.yaml")


def steps(*items: str) -> tuple[StepRequest, ...]:
    """Return steps from 'action moving fixed [fit]' strings."""
    requests = []
    for item in items:
        action, moving, fixed, *fit = item.split()
        requests.append(StepRequest(action, moving, fixed, fit[0] if fit else None))
    return tuple(requests)


CORRECT_PLANS: dict[str, tuple[StepRequest, ...]] = {
    "desk_lamp": steps(
        "screw light_bulb base_with_cables bulb_into_socket", "clip shade base_with_cables shade_onto_ring"
    ),
    "flashlight": steps("insert batteries case batteries_into_bay", "screw head case head_onto_case"),
    "candle": steps("insert wick wax wick_into_wax", "ignite match wick match_lights_wick"),
    "kerosene_lamp": steps(
        "screw burner fuel_tank burner_onto_tank",
        "insert wick burner wick_into_burner",
        "ignite lighter wick lighter_lights_wick",
        "place glass_chimney burner chimney_onto_burner",
    ),
}
"""The whole assembly of each of the paper's four objects, in an order that works."""

TOY_CAR_PLAN = steps(
    "insert wind_up_motor chassis motor_into_chassis",
    "connect wheels wind_up_motor wheels_onto_axle",
    "place sticker chassis sticker_onto_chassis",
)
"""The toy car (the tutorial object) built whole."""


def goal_plans(obj: AssemblyObject, most: int = 6) -> list[tuple[StepRequest, ...]]:
    """Return up to ``most`` plans making the first fit of each requirement, each after what holds its mate.

    A fit whose fixed part is not the base needs a fit that joins that part first (the first
    the catalog lists). The plans are the orders of those fits in which every fixed part is
    in the assembly when it is used, the requirements' order first: the robot may manage one
    order and not another (its fingers may touch a part already in place).
    """
    chosen: list[str] = []

    def need(fit_id: str) -> None:
        fit = obj.fit(fit_id)
        if fit_id in chosen:
            return
        if fit.fixed_part != obj.base and all(obj.fit(made).moving_part != fit.fixed_part for made in chosen):
            holder = next(f for f in obj.fits if f.moving_part == fit.fixed_part and f.primitive != "ignite")
            need(holder.id)
        chosen.append(fit_id)

    for requirement in obj.mechanism:
        need(requirement.any_of[0])
    plans = []
    for order in itertools.permutations(map(obj.fit, chosen)):
        present = {obj.base}
        for fit in order:
            if fit.fixed_part not in present:
                break
            present.add(fit.moving_part)
        else:
            plans.append(tuple(StepRequest(f.primitive, f.moving_part, f.fixed_part, f.id) for f in order))
        if len(plans) == most:
            break
    return plans


SHADE_BEFORE_BULB = Episode(
    "light_bulb",
    (
        Step("detach", "shade"),
        Step("detach", "light_bulb"),
        Step("replace", "light_bulb"),
        Step("attach", "shade"),
        Step("attach", "light_bulb"),
        Step("test", None, "goal"),
    ),
)
"""The desk lamp's bulb replaced, but its shade put back first: physics finds the socket covered."""

SPARE_SHADE_ONLY = Episode(
    "light_bulb",
    (Step("detach", "shade"), Step("replace", "shade"), Step("attach", "shade"), Step("test", None, "goal")),
)
"""The desk lamp with a broken bulb and only its shade replaced: whole, its mechanism works, yet no light."""
