"""The tiny JEPA size every test folder builds from (tests/conftest.py puts tests/ on ``sys.path``, so test modules and
helpers of any folder import it as ``_nets``); each folder adds the history, batch or loss sizes it needs."""

#: a width-8 CNN JEPA (LeWM, PLDM) at 16x16 with one predictor layer of two 4-wide heads
TINY_JEPA = dict(
    image_size=16,
    embed_dim=8,
    cnn_width=8,
    depth=1,
    heads=2,
    dim_head=4,
    mlp_dim=16,
    projector_hidden=16,
    frameskip=1,
)
