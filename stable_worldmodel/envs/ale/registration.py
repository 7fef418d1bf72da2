"""Registering ale-py's ``ALE/<Game>-v5`` ids with Gymnasium without importing ale-py.

:func:`register_ale_ids` (run by ``import stable_worldmodel``) registers every id of
:data:`GAMES` with the string entry point :func:`stable_worldmodel.envs.ale.env.make_ale_env`,
the game as a keyword and ale-py's own v5 defaults (:data:`V5_KWARGS`), so
``gym.spec("ALE/Pong-v5").kwargs`` reads as ale-py's. The ids stay out of the swm registry
(``list_envs`` / ``swm envs``): they have no factors and no goal.

ale-py registers the same ids when it is first imported, and Gymnasium warns for each id it
finds taken ("Overriding environment ..."). So where ale-py is installed, a finder on
``sys.meta_path`` (for ``ale_py`` only; a mere look-up such as ``importlib.util.find_spec``
changes nothing) removes these lazy ids just before ``ale_py`` is first imported, by anyone
(the first ``gym.make`` of an ALE id, or the user's own ``import ale_py``), then removes itself:
ale-py registers its ids on a clean slate and from then on Gymnasium makes its envs directly.
When ale-py was imported before ``stable_worldmodel``, nothing is registered (it has done it).
"""

from __future__ import annotations

import importlib.util
import sys

#: ale-py's v5 games (``ale_py.roms.get_all_rom_ids()`` of ale-py 0.12 without the four
#: two-player-only ROMs ale-py skips: combat, joust, maze_craze, warlords)
GAMES = (
    "adventure", "air_raid", "alien", "amidar", "assault", "asterix", "asteroids", "atlantis2", "atlantis",
    "backgammon", "bank_heist", "basic_math", "battle_zone", "beam_rider", "berzerk", "blackjack", "bowling",
    "boxing", "breakout", "carnival", "casino", "centipede", "chopper_command", "crazy_climber", "crossbow",
    "darkchambers", "defender", "demon_attack", "donkey_kong", "double_dunk", "earthworld", "elevator_action",
    "enduro", "entombed", "et", "fishing_derby", "flag_capture", "freeway", "frogger", "frostbite", "galaxian",
    "gopher", "gravitar", "hangman", "haunted_house", "hero", "human_cannonball", "ice_hockey", "jamesbond",
    "journey_escape", "kaboom", "kangaroo", "keystone_kapers", "king_kong", "klax", "koolaid", "krull",
    "kung_fu_master", "laser_gates", "lost_luggage", "mario_bros", "miniature_golf", "montezuma_revenge", "mr_do",
    "ms_pacman", "name_this_game", "othello", "pacman", "phoenix", "pitfall2", "pitfall", "pong", "pooyan",
    "private_eye", "qbert", "riverraid", "road_runner", "robotank", "seaquest", "sir_lancelot", "skiing", "solaris",
    "space_invaders", "space_war", "star_gunner", "superman", "surround", "tennis", "tetris", "tic_tac_toe_3d",
    "time_pilot", "trondead", "turmoil", "tutankham", "up_n_down", "venture", "video_checkers", "video_chess",
    "video_cube", "video_pinball", "wizard_of_wor", "word_zapper", "yars_revenge", "zaxxon",
)  # fmt: skip
#: ale-py's registered defaults of every v5 id (108k frames = 30 minutes of play = 27k steps)
V5_KWARGS = {
    "repeat_action_probability": 0.25,
    "full_action_space": False,
    "frameskip": 4,
    "max_num_frames_per_episode": 108_000,
}
ENTRY_POINT = "stable_worldmodel.envs.ale.env:make_ale_env"
VECTOR_ENTRY_POINT = "stable_worldmodel.envs.ale.env:make_ale_vector_env"


def game_name(rom: str) -> str:
    """ale-py's id name of a ROM: ``"space_invaders"`` -> ``"SpaceInvaders"``."""
    return rom.title().replace("_", "")


def ale_id(rom: str) -> str:
    return f"ALE/{game_name(rom)}-v5"


ALE_IDS = tuple(ale_id(rom) for rom in GAMES)


def register_ale_ids() -> tuple:
    """Register the lazy ``ALE/<Game>-v5`` ids (module docstring); idempotent.

    Called by the registry's ``register_all``; the ids get no swm registry entry (no factors, no goal).
    Returns an empty tuple.
    """
    if sys.modules.get("ale_py") is not None:  # ale-py is imported: its ids are registered
        return ()
    import gymnasium as gym

    for rom in GAMES:
        env_id = ale_id(rom)
        if env_id not in gym.registry:
            gym.register(
                id=env_id,
                entry_point=ENTRY_POINT,
                vector_entry_point=VECTOR_ENTRY_POINT,
                kwargs={"game": rom, **V5_KWARGS},
            )
    if importlib.util.find_spec("ale_py") is not None and not any(isinstance(f, _AleImport) for f in sys.meta_path):
        sys.meta_path.insert(0, _AleImport())
    return ()


def drop_lazy_ids() -> None:
    """Remove the ids that still point at our lazy entry point (ale-py's own are kept)."""
    import gymnasium as gym

    for env_id in ALE_IDS:
        spec = gym.registry.get(env_id)
        if spec is not None and spec.entry_point == ENTRY_POINT:
            del gym.registry[env_id]


class _AleImport:
    """A ``sys.meta_path`` finder for ``ale_py`` only: it returns the spec the other finders give,
    with a loader that, when ``ale_py`` is really imported (not merely looked up, as
    ``importlib.util.find_spec`` does), first drops our lazy ids and this finder, then runs the
    real loader (which is put back on the module first, so ale-py sees its own)."""

    def find_spec(self, name, path=None, target=None):
        if name != "ale_py":
            return None
        for finder in sys.meta_path:
            if finder is self or not hasattr(finder, "find_spec"):
                continue
            spec = finder.find_spec(name, path, target)
            if spec is not None:
                if spec.loader is not None and hasattr(spec.loader, "exec_module"):
                    spec.loader = _DropIdsFirst(spec.loader, self)
                return spec
        return None


class _DropIdsFirst:
    """Loader wrapper of :class:`_AleImport` (everything but ``exec_module`` is the real loader's)."""

    def __init__(self, loader, finder: _AleImport):
        self._loader, self._finder = loader, finder

    def __getattr__(self, name):
        return getattr(self._loader, name)

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module):
        if self._finder in sys.meta_path:
            sys.meta_path.remove(self._finder)
        drop_lazy_ids()
        module.__loader__ = self._loader
        if module.__spec__ is not None:
            module.__spec__.loader = self._loader
        self._loader.exec_module(module)
