"""``wm.frame``: a decoder trained on the frozen latents of another run (``swm train frame --from
RUN``), and ``swm eval --video`` showing what the planning model predicts beside the real frames."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from stable_worldmodel.errors import ConfigError
from stable_worldmodel.wm.frame import FrameDecoder, FrameModel
from stable_worldmodel.wm.utils import load_checkpoint

pytestmark = pytest.mark.usefixtures("one_torch_thread")


@pytest.mark.parametrize(("size", "width"), [(16, 8), (12, 4), (8, 8)])
def test_decoder_shapes(size, width):
    dec = FrameDecoder(embed_dim=8, image_size=size, channels=3, width=width)
    assert dec(torch.randn(2, 5, 8)).shape == (2, 5, 3, size, size)


def test_decoder_refuses_bad_sizes():
    with pytest.raises(ConfigError, match="image_size to be a positive int, got 0"):
        FrameDecoder(embed_dim=8, image_size=0)


def test_trains_on_the_frozen_latents_of_its_source(fit, toy):
    from stable_worldmodel.train import train

    fit("lewm", "lw", steps=4)
    source, _ = load_checkpoint("lw")
    result = train(
        "frame",
        None,
        steps=60,
        batch_size=8,
        device="cpu",
        seed=0,
        progress=False,
        source="lw",
        width=8,
        lr=3e-3,
        warmup_steps=0,
    )
    assert result.run == "lw-frame"
    losses = [r["train/loss"] for r in result.history if "train/loss" in r]
    assert np.mean(losses[-3:]) < 0.7 * np.mean(losses[:3])  # the decoder learns
    frame, protocol = load_checkpoint("lw-frame")
    assert isinstance(frame, FrameModel) and protocol["dataset"] == toy and protocol["config"]["source"] == "lw"
    for name, value in source.state_dict().items():  # the source model was not trained
        torch.testing.assert_close(frame.world_model.state_dict()[name], value)


def test_needs_a_source_with_one_latent_per_frame(fit):
    from stable_worldmodel.train import train

    with pytest.raises(ConfigError, match="requires source"):
        train("frame", "toy", steps=1, progress=False)
    fit(
        "prejepa",
        "pj",
        steps=1,
        image_size=16,
        embed_dim=8,
        cnn_width=8,
        cnn_grid=2,
        depth=1,
        heads=2,
        dim_head=4,
        mlp_dim=16,
        history_size=2,
        frameskip=1,
        warmup_steps=0,
    )
    with pytest.raises(ConfigError, match="one latent vector per frame"):
        train("frame", None, steps=1, device="cpu", progress=False, source="pj", width=4)


def test_eval_video_shows_the_predicted_frames(swm, fit, tmp_path):
    import av

    fit("lewm", "lw", steps=2)
    trained = swm("train", "frame", "--from", "lw", "--steps", "2", "--device", "cpu")
    usage = "swm eval ENV --policy wm:lw --video DIR --decoder lw-frame"
    assert trained.exit_code == 0 and f"shows what lw predicts: {usage}" in trained.stdout, trained.output
    for prefix in ("wm", "gc"):  # a decoder neither plans nor acts: both errors say how it is used
        wrong = swm("eval", "swm/Toy-v0", "--policy", f"{prefix}:lw-frame", "-n", "1", "--image-size", "16")
        assert (
            wrong.exit_code == 1 and "got a frame decoder" in wrong.output and usage in wrong.output.replace("\n", "")
        )
    args = [
        "eval",
        "swm/Toy-v0",
        "--policy",
        "wm:lw",
        "-n",
        "1",
        "--samples",
        "4",
        "--iterations",
        "1",
        "--horizon",
        "2",
        "--image-size",
        "16",
        "--max-steps",
        "4",
    ]
    plain = swm(
        *args, "--video", str(tmp_path / "plain"), "--json", str(tmp_path / "plain.json"), "--decoder", "lw-frame"
    )
    assert plain.exit_code == 0, plain.output
    assert json.loads((tmp_path / "plain.json").read_text())["decoder"] == "lw-frame"
    with av.open(str(tmp_path / "plain" / "env_0.mp4")) as video:
        frame = next(video.decode(video=0)).to_ndarray(format="rgb24")
    assert frame.shape[1] == 2 * 16  # the env's frame, then the predicted one (the goal below)
    refused = swm(*args, "--decoder", "lw-frame")
    assert refused.exit_code != 0 and "--video" in refused.output


def test_dreamer_videos_show_its_own_decoded_predictions(swm, fit, tmp_path):
    import av

    fit("dreamer", "dr", steps=2)
    args = [
        "eval",
        "swm/Toy-v0",
        "--policy",
        "wm:dr",
        "-n",
        "1",
        "--samples",
        "4",
        "--iterations",
        "1",
        "--horizon",
        "2",
        "--image-size",
        "16",
        "--max-steps",
        "4",
        "--subgoals",
        "none",
    ]
    out = swm(*args, "--video", str(tmp_path / "v"), "--json", str(tmp_path / "v.json"))
    assert out.exit_code == 0, out.output
    assert json.loads((tmp_path / "v.json").read_text())["decoder"] == "dr"  # no dr-frame run: its own decoder
    with av.open(str(tmp_path / "v" / "env_0.mp4")) as video:
        frame = next(video.decode(video=0)).to_ndarray(format="rgb24")
    assert frame.shape[1] == 2 * 16


def test_a_frame_decoder_reads_dreamer_predictions_through_its_embedding_head(fit):
    from stable_worldmodel import keys
    from stable_worldmodel.wm.frame import PredictionPanel

    fit("dreamer", "dr", steps=2)
    model, _ = load_checkpoint("dr")
    decoder = FrameModel(model, FrameDecoder(embed_dim=model.rssm.embed_dim, image_size=16, width=4)).eval()
    seen = []
    decoder.decoder.register_forward_hook(lambda mod, args, out: seen.append(args[0].shape))
    panel = PredictionPanel(model, decoder, (0.5,) * 3, (0.5,) * 3)
    frames = panel({keys.PIXELS: torch.zeros(2, 1, 3, 16, 16)}, torch.zeros(2, 2, model.action_dim))
    assert frames.shape == (2, 16, 16, 3) and frames.dtype == np.uint8
    assert seen == [torch.Size([2, model.rssm.embed_dim])]  # the predicted frame embedding, not the RSSM state
    own = PredictionPanel(model, None, (0.5,) * 3, (0.5,) * 3)
    assert own({keys.PIXELS: torch.zeros(2, 1, 3, 16, 16)}, torch.zeros(2, 2, model.action_dim)).shape == (2, 16, 16, 3)
    other = FrameModel(model, decoder.decoder)  # a model without decodes_frames needs a frame model
    with pytest.raises(ConfigError, match="own decode"):
        PredictionPanel(other, None, (0.5,) * 3, (0.5,) * 3)
