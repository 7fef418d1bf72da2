"""World models (JEPA-style DINO-WM / PLDM / LeWM, TD-MPC, Dreamer).

Not implemented yet: the world-model issue builds them here (one folder per model,
a light config plus a torch module). Planning already works with any object exposing
``get_cost(info_dict, candidates) -> (B, S)`` (see :mod:`stable_worldmodel.solver`).
"""

__all__: list[str] = []
