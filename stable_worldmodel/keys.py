"""Info-dict key names shared across the package (never write these as literals)."""

PIXELS = "pixels"
GOAL = "goal"
ACTION = "action"
REWARD = "reward"
TERMINATED = "terminated"
TRUNCATED = "truncated"
STEP_IDX = "step_idx"
EPISODE_ID = "id"
RENDER_TIME = "render_time"
STATE = "state"
PROPRIO = "proprio"
GOAL_STATE = "goal_state"
GOAL_PROPRIO = "goal_proprio"
VARIATION = "variation"
VARIATION_VALUES = "variation_values"
EP_LEN = "ep_len"
EP_IDX = "ep_idx"  # per-row index of the episode in its dataset (written by record_dataset)
EP_OFFSET = "ep_offset"


def goal_key(key: str) -> str:
    """The goal version of info key ``key`` (``"state"`` -> ``"goal_state"``)."""
    return f"{GOAL}_{key}"
