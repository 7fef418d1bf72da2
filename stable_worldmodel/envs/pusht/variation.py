"""The 17 factors of variation of PushT and how reset draws the per-seed ones.

======================  =========================  ==========================================
factor                  default                    range
======================  =========================  ==========================================
agent.color             RoyalBlue (65, 105, 225)   any RGB
agent.scale             1.0 (radius 15)            [0.6, 1.6] x the agent unit 15
agent.shape             "circle"                   index into ``shapes.SHAPES``
agent.angle             0                          [-pi, pi] (matters for non-circle agents)
agent.start_position    per seed                   [50, 450]^2
agent.velocity          (0, 0)                     [-200, 200]^2 px/s at reset
block.color             LightSlateGray             any RGB
block.scale             1.0 (the 120x30 bars)      [0.7, 1.3] x the block unit 30
block.shape             "tee"                      index into ``shapes.SHAPES``
block.angle             per seed                   [-pi, pi]
block.start_position    per seed                   [100, 400]^2
goal.color              LightGreen                 any RGB
goal.scale              1.0                        [0.7, 1.3] x the block's size (drawn only)
goal.angle              pi/4                       [-pi, pi]
goal.position           (256, 256)                 [150, 362]^2
background.color        white                      any RGB
rendering.render_goal   1                          0 or 1: draw the goal silhouette (upstream's)
======================  =========================  ==========================================

"Per seed" factors (:data:`SEEDED`) are drawn from the reset seed at every reset, as in
gym-pusht, unless ``variation_values`` sets them; draws are redone (with the same generator)
until the agent does not touch the block and the block clears the walls. Every other factor
keeps its default unless named in ``options["variation"]`` or set in ``options["variation_values"]``.
"""

from __future__ import annotations

import numpy as np

from ... import spaces
from ..base import rgb_factor as _rgb
from .physics import WALLS
from .shapes import SHAPES, ShapeSpec, distance_to_shape, rotation, to_world

AGENT_UNIT = 15.0
BLOCK_UNIT = 30.0
SEEDED = ("agent.start_position", "block.start_position", "block.angle")
_MARGIN = 4.0  # clearance of a drawn start between the agent and the block, and to the walls


def _scalar(low: float, high: float, init: float) -> spaces.Box:
    return spaces.Box(low, high, shape=(), dtype=np.float64, init_value=np.float64(init))


def _xy(low: float, high: float, init) -> spaces.Box:
    return spaces.Box(low, high, shape=(2,), dtype=np.float64, init_value=np.asarray(init, np.float64))


def build_variation_space() -> spaces.Dict:
    """A fresh :class:`~stable_worldmodel.spaces.Dict` of the factors above."""
    return spaces.Dict(
        {
            "agent": spaces.Dict(
                {
                    "color": _rgb((65, 105, 225)),
                    "scale": _scalar(0.6, 1.6, 1.0),
                    "shape": spaces.Discrete(len(SHAPES), init_value=SHAPES.index("circle")),
                    "angle": _scalar(-np.pi, np.pi, 0.0),
                    "start_position": _xy(50.0, 450.0, (256.0, 400.0)),
                    "velocity": _xy(-200.0, 200.0, (0.0, 0.0)),
                }
            ),
            "block": spaces.Dict(
                {
                    "color": _rgb((119, 136, 153)),
                    "scale": _scalar(0.7, 1.3, 1.0),
                    "shape": spaces.Discrete(len(SHAPES), init_value=SHAPES.index("tee")),
                    "angle": _scalar(-np.pi, np.pi, 0.0),
                    "start_position": _xy(100.0, 400.0, (256.0, 300.0)),
                }
            ),
            "goal": spaces.Dict(
                {
                    "color": _rgb((144, 238, 144)),
                    "scale": _scalar(0.7, 1.3, 1.0),
                    "angle": _scalar(-np.pi, np.pi, np.pi / 4),
                    "position": _xy(150.0, 362.0, (256.0, 256.0)),
                }
            ),
            "background": spaces.Dict({"color": _rgb((255, 255, 255))}),
            "rendering": spaces.Dict({"render_goal": spaces.Discrete(2, init_value=1)}),
        }
    )


def _uniform(space, rng: np.random.Generator) -> np.ndarray:
    return np.asarray(rng.uniform(space.low, space.high), np.float64)


def _clear(agent: ShapeSpec, agent_xy, block: ShapeSpec, block_xy, block_angle: float) -> bool:
    """Whether the agent's bounding disk misses the block and the block lies inside the walls."""
    pts = to_world(block.outline, block_xy, block_angle)
    lo, hi = WALLS[0][1][0] + 2 + _MARGIN, WALLS[2][1][0] - 2 - _MARGIN
    if pts.min() < lo or pts.max() > hi:
        return False
    local = (np.asarray(agent_xy, np.float64) - np.asarray(block_xy, np.float64)) @ rotation(block_angle)
    return float(distance_to_shape(block, local)[0]) > agent.reach() + _MARGIN


def draw_seeded(variation_space, given: set[str], agent: ShapeSpec, block: ShapeSpec, rng: np.random.Generator) -> None:
    """Draw the :data:`SEEDED` factors not in ``given`` from ``rng`` and store them in the space."""
    todo = [name for name in SEEDED if name not in given]
    if not todo:
        return
    leaves = {name: variation_space[name.split(".")[0]][name.split(".")[1]] for name in SEEDED}
    values = {name: leaves[name].value for name in SEEDED}
    for _ in range(100):
        for name in todo:
            values[name] = _uniform(leaves[name], rng)
        if _clear(
            agent, values["agent.start_position"], block, values["block.start_position"], float(values["block.angle"])
        ):
            break
    variation_space.set_value({name: values[name] for name in todo})
