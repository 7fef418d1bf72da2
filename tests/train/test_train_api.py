"""``stable_worldmodel.train.train``: the loss falls, resume equals an uninterrupted run, the run
folder, the seeded episode split, and the errors. Tiny models (width 8, 16x16) on a recorded toy
dataset of 10 expert episodes (see ``conftest.py``)."""

from __future__ import annotations

import csv
import json
import math
import shutil

import h5py
import numpy as np
import pytest
import torch

from stable_worldmodel import keys
from stable_worldmodel.errors import ConfigError, DatasetFormatError, UnknownNameError
from stable_worldmodel.train import trainer as trainer_module
from stable_worldmodel.train.data import TrainData, split_episodes
from stable_worldmodel.wm import get_config
from stable_worldmodel.wm.utils import list_checkpoints, load_pretrained


def train_losses(folder) -> list[tuple[int, float]]:
    """``(step, train/loss)`` of every record of ``metrics.jsonl``."""
    records = [json.loads(line) for line in (folder / "metrics.jsonl").read_text().splitlines()]
    return [(r["step"], r["train/loss"]) for r in records if "train/loss" in r]


def weights(path) -> dict[str, torch.Tensor]:
    return torch.load(path, map_location="cpu", weights_only=True)


def assert_same_weights(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> None:
    assert a.keys() == b.keys()
    differ = [k for k in a if not torch.equal(a[k], b[k])]
    assert not differ, f"tensors differ: {differ}"


def outputs(model: torch.nn.Module) -> torch.Tensor:
    """Costs of fixed candidates from fixed images: they go through every module of the model."""
    gen = torch.Generator().manual_seed(7)
    info = {
        keys.PIXELS: torch.randn(2, 3, 1, 3, 16, 16, generator=gen),
        keys.GOAL: torch.randn(2, 3, 1, 3, 16, 16, generator=gen),
    }
    model.eval()
    with torch.no_grad():
        return model.get_cost(info, torch.randn(2, 3, 2, 2, generator=gen))


@pytest.fixture
def captured(monkeypatch):
    """The trainers that ran (their ``model`` is the trained module itself)."""
    seen = []
    fit = trainer_module.Trainer.fit

    def spy(self, log):
        seen.append(self)
        return fit(self, log)

    monkeypatch.setattr(trainer_module.Trainer, "fit", spy)
    return seen


class Crash(Exception):
    """Stands for a killed run."""


def crash_after(monkeypatch, batches: int) -> None:
    """Make training raise :class:`Crash` when it asks for batch number ``batches + 1`` (counted by the
    generator state it is drawn from: a batch read ahead, dropped and read again counts once)."""
    draw, seen = TrainData.train_batch, set()

    def train_batch(self, generator, batch_size):
        seen.add(bytes(generator.get_state().numpy()))
        if len(seen) > batches:
            raise Crash
        return draw(self, generator, batch_size)

    monkeypatch.setattr(TrainData, "train_batch", train_batch)


# -- learning ----------------------------------------------------------------------------------
@pytest.mark.parametrize("model", ["dummy", "lewm", "pldm"])
def test_loss_falls(fit, model):
    # 40 steps at lr 3e-3: the last logged losses are 0.02-0.72x the first ones over seeds 0..11
    result = fit(model, f"falls-{model}", steps=40, lr=3e-3, log_every=5, val_every=0, ckpt_every=0)
    losses = [loss for _, loss in train_losses(result.folder)]
    assert len(losses) == 8 and all(math.isfinite(v) for v in losses)
    first, last = np.mean(losses[:2]), np.mean(losses[-2:])
    assert last < 0.85 * first, f"{model} did not learn: {losses}"
    assert result.train_loss == losses[-1] and result.steps == 40
    assert result.val_loss is not None and math.isfinite(result.val_loss)


@pytest.mark.parametrize(
    "backend",
    [
        # forward and backward graphs captured and run by torch's own kernels: the compile path without
        # inductor's code generation (a few seconds)
        "aot_eager",
        pytest.param("inductor", marks=pytest.mark.slow),  # what compile=True runs (~30 s on a 2-core CPU)
    ],
)
def test_compiled_training_step_learns_and_is_recorded(fit, compile_recorder, backend):
    compile_recorder.backend = backend
    result = fit("lewm", "compiled", steps=40, lr=3e-3, log_every=5, val_every=0, ckpt_every=0, compile=True)
    assert compile_recorder.names == ["loss"]  # the model's loss, once
    losses = [loss for _, loss in train_losses(result.folder)]
    assert len(losses) == 8 and all(math.isfinite(v) for v in losses)
    assert np.mean(losses[-2:]) < 0.85 * np.mean(losses[:2]), f"did not learn: {losses}"
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert protocol["compile"] is True
    # the saved weights are the model's own (no torch.compile wrapper in their names)
    assert not any("_orig_mod" in k for k in weights(result.folder / "weights.pt"))


@pytest.mark.parametrize(
    ("model", "every", "crash", "logged"),
    [
        # dropout and SIGReg's random directions draw from the global RNG: resume must restore it
        ("lewm", dict(log_every=2, val_every=4, ckpt_every=6), 8, [2, 4, 6, 8, 10, 12]),
        ("pldm", dict(log_every=2, val_every=4, ckpt_every=6), 8, [2, 4, 6, 8, 10, 12]),
        # a checkpoint between two logs: the resumed log at step 8 averages steps 5..8, as the whole run's
        ("dummy", dict(log_every=4, val_every=0, ckpt_every=6), 9, [4, 8, 12]),
    ],
)
def test_resume_equals_an_uninterrupted_run(fit, monkeypatch, model, every, crash, logged):
    kwargs = dict(steps=12, lr=3e-3, **every, **({"dropout": 0.1} if model != "dummy" else {}))
    whole = fit(model, "whole", **kwargs)

    with monkeypatch.context() as mp:
        crash_after(mp, crash)  # killed at step `crash`: the last checkpoint is step 6
        with pytest.raises(Crash):
            fit(model, "split", **kwargs)
    folder = whole.folder.parent / "split"
    assert torch.load(folder / "train_state.ckpt", weights_only=True)["step"] == 6
    assert train_losses(folder)[-1][0] > 6  # logged after the checkpoint: dropped on resume

    resumed = fit(model, "split", resume=True, **kwargs)
    assert resumed.steps == 12
    assert_same_weights(weights(whole.folder / "weights.pt"), weights(folder / "weights.pt"))
    assert train_losses(folder) == train_losses(whole.folder)  # each logged step once, with the same loss
    assert [s for s, _ in train_losses(folder)] == logged
    assert resumed.train_loss == whole.train_loss and resumed.val_loss == whole.val_loss


def test_the_next_batch_is_read_while_a_step_computes_and_changes_no_weight(fit, monkeypatch):
    """A batch is read in a background thread during the step before it; validation and checkpoints in
    between drop it and read it again: the weights are those of a run that reads every batch in its step."""
    import threading

    draw, in_main = TrainData.train_batch, []

    def spy(self, generator, batch_size):
        in_main.append(threading.current_thread() is threading.main_thread())
        return draw(self, generator, batch_size)

    monkeypatch.setattr(TrainData, "train_batch", spy)
    kwargs = dict(steps=9, lr=3e-3, log_every=2, val_every=3, ckpt_every=4, dropout=0.1)
    ahead = fit("lewm", "ahead", **kwargs)
    assert in_main[0] and in_main.count(False) >= 5  # the first batch in the step, most of the others ahead
    monkeypatch.setattr(trainer_module.Trainer, "_prefetching", lambda self: False)
    in_main.clear()
    inline = fit("lewm", "inline", **kwargs)
    assert all(in_main) and len(in_main) == 9
    assert_same_weights(weights(ahead.folder / "weights.pt"), weights(inline.folder / "weights.pt"))
    assert train_losses(ahead.folder) == train_losses(inline.folder)


def test_resume_of_a_finished_run_changes_nothing(fit):
    done = fit("dummy", "done", steps=6, log_every=2)
    before, metrics = weights(done.folder / "weights.pt"), (done.folder / "metrics.jsonl").read_text()
    again = fit("dummy", "done", steps=6, log_every=2, resume=True)
    assert again.steps == 6 and again.train_loss == done.train_loss and again.val_loss == done.val_loss
    assert_same_weights(before, weights(done.folder / "weights.pt"))
    assert (done.folder / "metrics.jsonl").read_text() == metrics


# -- the run folder ----------------------------------------------------------------------------
def test_run_folder_holds_model_protocol_metrics_plot_and_checkpoints(fit, captured, toy, _stablewm_home):
    result = fit("lewm", "layout", steps=8, log_every=2, val_every=4, ckpt_every=4)
    folder = _stablewm_home / "checkpoints" / "layout"
    assert result.folder == folder and result.run == "layout"
    for name in (
        "weights.pt",
        "config.json",
        "protocol.json",
        "train_state.ckpt",
        "metrics.jsonl",
        "metrics.csv",
        "loss.png",
    ):
        assert (folder / name).is_file(), name
    assert (folder / "loss.png").read_bytes().startswith(b"\x89PNG")
    assert list(folder.glob("*.pt")) == [folder / "weights.pt"]  # load_pretrained needs exactly one

    # periodic checkpoints: step 4 only (step 8 is the run folder itself)
    assert sorted(p.name for p in folder.glob("step_*")) == ["step_000004"]
    step4 = folder / "step_000004"
    assert json.loads((step4 / "protocol.json").read_text())["steps_done"] == 4
    assert torch.load(folder / "train_state.ckpt", weights_only=True)["step"] == 8
    assert list_checkpoints() == ["layout", "layout/step_000004"]

    # metrics: the same records in jsonl and csv, train loss every 2 steps, val loss every 4
    records = [json.loads(line) for line in (folder / "metrics.jsonl").read_text().splitlines()]
    assert records == result.history
    assert [r["step"] for r in records if "train/loss" in r] == [2, 4, 6, 8]
    assert [r["step"] for r in records if "val/loss" in r] == [4, 8]
    with (folder / "metrics.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [int(r["step"]) for r in rows] == [r["step"] for r in records]
    assert [float(r["train/loss"]) for r in rows] == pytest.approx([r["train/loss"] for r in records])

    # protocol: what planning needs to know
    protocol = json.loads((folder / "protocol.json").read_text())
    assert protocol["model"] == "lewm" and protocol["dataset"] == toy and protocol["seed"] == 0
    assert protocol["frameskip"] == 1 and protocol["history_size"] == 2 and protocol["num_preds"] == 1
    assert protocol["steps"] == protocol["steps_done"] == 8 and protocol["action_dim"] == 2
    assert protocol["dataset_image_shape"] == [16, 16, 3] and protocol["image_size"] == 16
    assert protocol["final"] == {"train_loss": result.train_loss, "val_loss": result.val_loss}
    assert sorted(protocol["train_episodes"] + protocol["val_episodes"]) == list(range(10))

    # the action normalizer is fitted on the train episodes' rows only
    with h5py.File(_stablewm_home / f"{toy}.h5") as f:
        action, offsets, lengths = f["action"][:], f["ep_offset"][:], f["ep_len"][:]
    rows = np.concatenate([np.arange(offsets[e], offsets[e] + lengths[e]) for e in protocol["train_episodes"]])
    train_actions = action[rows][~np.isnan(action[rows]).any(axis=1)]
    normalizer = protocol["normalizers"]["action"]
    np.testing.assert_allclose(normalizer["mean"], train_actions.mean(axis=0), rtol=1e-6)
    np.testing.assert_allclose(normalizer["std"], train_actions.std(axis=0), rtol=1e-6)

    # load_pretrained rebuilds the trained model; the step-4 checkpoint is an earlier one
    (trainer,) = captured
    expected = outputs(trainer.model)
    assert torch.equal(outputs(load_pretrained("layout")), expected)
    assert not torch.equal(outputs(load_pretrained("layout/step_000004")), expected)


def test_default_run_name_and_epochs(fit, toy):
    data = TrainData(toy, get_config("dummy", "tiny", image_size=16, frameskip=1), seed=0, device=torch.device("cpu"))
    result = fit("dummy", None, epochs=2)
    assert result.run == f"{toy}-dummy"
    assert result.steps == math.ceil(2 * data.num_train / 8)
    assert json.loads((result.folder / "protocol.json").read_text())["steps"] == result.steps


def test_the_trainer_resizes_images_to_the_model(fit, captured):
    result = fit("dummy", "small-images", steps=2, image_size=8)
    assert captured[0].model.encoder.in_features == 3 * 8 * 8
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert protocol["image_size"] == 8 and protocol["dataset_image_shape"] == [16, 16, 3]
    model = load_pretrained("small-images")
    assert model.encode({keys.PIXELS: torch.zeros(1, 3, 8, 8)})["emb"].shape == (1, 10)


# -- the train / validation split ---------------------------------------------------------------
@pytest.mark.parametrize("episodes", [2, 5, 10, 37])
def test_split_is_by_episode_seeded_disjoint_and_complete(episodes):
    for seed in range(5):
        train, val = split_episodes(episodes, 0.1, seed)
        again = split_episodes(episodes, 0.1, seed)
        assert np.array_equal(train, again[0]) and np.array_equal(val, again[1])
        assert not set(train) & set(val)
        assert sorted([*train, *val]) == list(range(episodes))
        assert list(train) == sorted(train) and list(val) == sorted(val)
        assert len(val) == max(1, round(0.1 * episodes))
    splits = {tuple(split_episodes(episodes, 0.1, seed)[1]) for seed in range(5)}
    assert len(splits) > 1, "the split does not depend on the seed"
    assert split_episodes(episodes, 0.0, 0)[1].size == 0


def test_split_is_recorded_and_samples_stay_in_their_split(fit, toy):
    cfg = get_config("dummy", "tiny", image_size=16, frameskip=1, val_fraction=0.3)
    for seed in (0, 1):
        data = TrainData(toy, cfg, seed=seed, device=torch.device("cpu"))
        train, val = split_episodes(10, 0.3, seed)
        assert data.train_episodes.tolist() == train.tolist() and data.val_episodes.tolist() == val.tolist()
        eps_train, _ = data.dataset._locate_many(data.train_index)
        eps_val, _ = data.dataset._locate_many(data.val_index)
        assert set(eps_train) == set(train.tolist()) and set(eps_val) == set(val.tolist())
        protocol = fit("dummy", f"split-{seed}", steps=1, seed=seed, val_fraction=0.3).folder / "protocol.json"
        recorded = json.loads(protocol.read_text())
        assert recorded["train_episodes"] == train.tolist() and recorded["val_episodes"] == val.tolist()
        assert recorded["train_samples"] == data.num_train and recorded["val_samples"] == data.num_val
    assert split_episodes(10, 0.3, 0)[1].tolist() != split_episodes(10, 0.3, 1)[1].tolist()


def test_validation_batches_have_no_lone_sample(toy):
    # a batch of one sample makes batch statistics (VCReg's variance, SIGReg) NaN
    cfg = get_config("pldm", "tiny", image_size=16, frameskip=1, val_fraction=0.3)
    data = TrainData(toy, cfg, seed=0, device=torch.device("cpu"))
    assert data.num_val >= 5
    for size in range(2, data.num_val + 1):
        batches = data.val_batches(size, 512)
        assert np.array_equal(np.concatenate(batches), data.val_index)
        assert all(2 <= len(b) <= size for b in batches), (size, [len(b) for b in batches])


def test_pldm_validation_loss_is_finite_when_one_sample_is_left_over(fit, toy, tiny):
    cfg = get_config("pldm", "tiny", **tiny["pldm"])
    num_val = TrainData(toy, cfg, seed=0, device=torch.device("cpu")).num_val
    assert num_val > 3
    result = fit("pldm", "leftover", steps=2, batch_size=num_val - 1)
    assert math.isfinite(result.val_loss)


# -- errors ------------------------------------------------------------------------------------


@pytest.fixture
def refused(fit, _stablewm_home):
    """``refused(exc, match, model, **kwargs)``: ``fit(model, "r", **kwargs)`` raises ``exc`` with a
    message matching ``match``, and leaves no run folder behind."""

    def check(exc, match, model="lewm", **kwargs):
        name = kwargs.pop("name", "r")
        with pytest.raises(exc, match=match):
            fit(model, name, **{"steps": 2, **kwargs})
        assert not (_stablewm_home / "checkpoints").exists() or not any((_stablewm_home / "checkpoints").iterdir())

    return check


def test_unknown_model_suggests_the_close_one(refused):
    refused(
        UnknownNameError,
        r"'lewn'\. Did you mean 'lewm'\? "
        r"Accepted: dinowm, dreamer, dummy, frame, gcbc, gciql, gcivl, lewm, pldm, prejepa, tdmpc2",
        model="lewn",
    )


def test_unknown_dataset_lists_the_cached_ones(refused, toy):
    refused(
        FileNotFoundError,
        rf"Training requires an existing dataset, got 'tyo': it does not exist in .*"
        r"\(looked for tyo\.h5, tyo\.lance, tyo, datasets/tyo\.h5, datasets/tyo\.lance, datasets/tyo\)\. "
        rf"Did you mean '{toy}'\? Datasets there: {toy}$",
        dataset="tyo",
    )


@pytest.mark.parametrize("missing", ["pixels", "action"])
def test_dataset_without_a_needed_column(refused, write_dataset, missing):
    kept = {"pixels": "action", "action": "pixels"}[missing]
    name = write_dataset("partial", columns=(kept, "reward"))
    refused(DatasetFormatError, rf"columns \['{missing}'\] in .*partial\.h5, got \['{kept}', 'reward'\]", dataset=name)


def test_episodes_shorter_than_a_window(refused, write_dataset):
    name = write_dataset("short", lengths=(2, 2, 2))  # lewm's windows are history 2 + 1 prediction = 3 rows
    refused(
        ConfigError,
        r"num_steps \* frameskip <= the longest episode \(2 rows\), got num_steps=3 \* frameskip=1 = 3",
        dataset=name,
    )


def test_images_with_other_channels_than_the_model(refused):
    refused(ConfigError, r"requires 1-channel images, got 3 channels", image_mean=(0.5,), image_std=(0.5,))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(precision="fp32"), r"precision in \('32', 'bf16', '16'\), got 'fp32'"),
        (dict(precision="16"), r"CUDA device for precision 16, got cpu; use bf16 or 32"),
        (dict(compile="yes"), r"compile to be True or False, got 'yes'"),
        (dict(device="gpu"), r"device among auto, cpu, cuda, cuda:N, mps, got 'gpu'"),
        (dict(steps=0), r"steps to be an integer >= 1, got 0"),
        (dict(batch_size=True), r"batch_size to be an integer >= 1, got True"),
        (dict(steps=None, epochs=-1.0), r"epochs > 0, got -1\.0"),
        (dict(steps=4, epochs=1.0), r"steps or epochs, got both"),
        (dict(seed=-1), r"seed to be an int >= 0, got -1"),
        (dict(name="a/b"), r"plain run name \(no path\), got 'a/b'"),
        (dict(embed_dims=8), r"no field 'embed_dims'\. Did you mean one of 'embed_dim'"),
        (dict(preset="huge"), r"preset in \['cpu', 'paper', 'small', 'tiny'\], got 'huge'"),
        (dict(lr=2.0), r"0 < lr < 1"),
    ],
    ids=lambda v: "-".join(f"{k}={v[k]}" for k in v) if isinstance(v, dict) else "",
)
def test_bad_arguments_are_config_errors(refused, kwargs, match):
    refused(ConfigError, match, **kwargs)


@pytest.mark.skipif(torch.cuda.is_available(), reason="needs a machine without CUDA")
def test_cuda_without_a_gpu(refused):
    refused(ConfigError, r"got 'cuda' but torch sees no CUDA GPU; use --device auto or cpu", device="cuda")


def test_an_existing_run_needs_resume(fit, refused):
    first = fit("dummy", "r", steps=1)
    before = (first.folder / "weights.pt").read_bytes()
    with pytest.raises(
        FileExistsError,
        match=r"Run folder .*/checkpoints/r exists: continue it with swm train --resume \(train\(resume=True\)\)",
    ):
        fit("dummy", "r", steps=1)
    assert (first.folder / "weights.pt").read_bytes() == before


def test_resume_needs_a_previous_run(refused):
    refused(
        FileNotFoundError,
        r"requires a previous run with .*/checkpoints/r/train_state\.ckpt, which does not exist",
        resume=True,
    )


def test_resume_continues_to_the_runs_plan_and_extends_it_with_more_steps(fit, monkeypatch):
    """No --steps: to the run's own plan (not the preset's); more steps: the run is extended, its
    schedule the new total's from the step it reached; fewer: refused."""
    with monkeypatch.context() as mp:
        crash_after(mp, 5)
        with pytest.raises(Crash):
            fit("dummy", "r", steps=8, log_every=2, ckpt_every=4)
    assert fit("dummy", "r", log_every=2, resume=True).steps == 8  # the run's 8, not the preset's
    with pytest.raises(
        ConfigError, match=r"requires --steps at least its planned 8 \(extending it is allowed\), got 6"
    ):
        fit("dummy", "r", steps=6, resume=True)
    longer = fit("dummy", "r", steps=12, log_every=2, resume=True)
    folder = longer.folder
    assert longer.steps == 12 and json.loads((folder / "protocol.json").read_text())["steps_done"] == 12
    state = torch.load(folder / "train_state.ckpt", weights_only=True)
    assert state["steps"] == 12 and state["step"] == 12
    assert [s for s, _ in train_losses(folder)] == [2, 4, 6, 8, 10, 12]  # one log per step, 9..12 appended


def test_init_from_starts_from_a_runs_weights(fit):
    source = fit("lewm", "src", steps=3)
    tuned = fit("lewm", "tuned", steps=1, lr=1e-12, init_from="src")  # a step too small to move the weights far
    src, new = weights(source.folder / "weights.pt"), weights(tuned.folder / "weights.pt")
    learned = [k for k in src if "running_" not in k and "num_batches" not in k]  # BatchNorm statistics move anyway
    assert all(torch.allclose(src[k].float(), new[k].float(), atol=1e-5) for k in learned)
    fresh = weights(fit("lewm", "fresh", steps=1, lr=1e-12).folder / "weights.pt")
    assert not all(torch.allclose(src[k].float(), fresh[k].float(), atol=1e-5) for k in learned)
    recorded = json.loads((tuned.folder / "protocol.json").read_text())["init_from"]
    assert recorded["run"] == "src" and len(recorded["weights_sha256"]) == 64
    with pytest.raises(ConfigError, match="requires a run of the same model and sizes, got lewm weights"):
        fit("lewm", "bigger", steps=1, init_from="src", embed_dim=24)
    with pytest.raises(FileNotFoundError, match="nosuch"):
        fit("lewm", "x", steps=1, init_from="nosuch")


def test_a_diverging_run_stops_at_its_next_log(fit, monkeypatch):
    from stable_worldmodel.wm.dummy import DummyWorldModel

    loss = DummyWorldModel.loss

    def nan_after_three(self, batch, calls=[]):  # noqa: B006 (a call counter)
        out = loss(self, batch)
        calls.append(1)
        if len(calls) > 3:
            out["loss"] = out["loss"] * float("nan")
        return out

    monkeypatch.setattr(DummyWorldModel, "loss", nan_after_three)
    with pytest.raises(
        FloatingPointError, match=r"Training diverged: loss \[.*nan.*\] in the 5 steps up to step 5; lower --lr"
    ):
        fit("dummy", "nan", steps=20, log_every=5)


@pytest.mark.parametrize("fmt", ["folder", "video", "lance"])
def test_trains_on_any_registered_format(fit, toy, _stablewm_home, fmt):
    """The trainer finds and opens datasets through the format registry: the toy recording
    converted to another format trains, on the same split and normalizers as the .h5 (its frames
    are JPEG there, so the losses are close, not equal)."""
    from stable_worldmodel.data.utils import convert

    written = convert(toy, _stablewm_home / f"toy-{fmt}", dest_format=fmt, progress=False)
    (_stablewm_home / f"{toy}.h5").rename(_stablewm_home / "elsewhere.h5")  # only the converted copy is found
    result = fit("lewm", f"from-{fmt}", dataset=f"toy-{fmt}", steps=10, log_every=5)  # toy-lance: toy-lance.lance
    assert result.steps == 10 and math.isfinite(result.train_loss)
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert protocol["dataset"] == f"toy-{fmt}" and protocol["dataset_path"] == str(written)
    (_stablewm_home / "elsewhere.h5").rename(_stablewm_home / f"{toy}.h5")
    reference = fit("lewm", f"from-h5-{fmt}", steps=10, log_every=5)
    same = json.loads((reference.folder / "protocol.json").read_text())
    for key in ("train_episodes", "val_episodes", "normalizers", "dataset_image_shape", "action_dim"):
        assert protocol[key] == same[key], key
    assert train_losses(result.folder)[0][1] == pytest.approx(train_losses(reference.folder)[0][1], rel=0.2)


def test_trains_on_a_sharded_dataset(fit, toy, _stablewm_home):
    """A folder of ``shard_*.h5`` files (what ``swm collect --ray`` writes) trains as one dataset."""
    shards = _stablewm_home / "sharded"
    shards.mkdir()
    for i in range(2):
        shutil.copy(_stablewm_home / f"{toy}.h5", shards / f"shard_{i}.h5")
    result = fit("lewm", "from-shards", dataset="sharded", steps=4, log_every=2)
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert protocol["dataset_path"] == str(shards) and protocol["episodes"] == 2 * 10
    assert result.steps == 4 and math.isfinite(result.train_loss)


def test_evaluation_during_training_logs_success_keeps_the_best_and_changes_no_weight(fit, toy):
    """``eval_every``: the checkpoint of every K-th step and the last one planned with in the dataset's env;
    success rate and 95% interval logged; the best kept as ``best/``; the random streams are restored, so the
    weights equal a run's without evaluations."""
    from stable_worldmodel.planning.learned import PlanSettings, world_model_policy

    plain = fit("lewm", "plain", steps=4, log_every=2)
    quick = PlanSettings(samples=8, iterations=1, horizon=2, receding_horizon=2, subgoals="none")
    evaluated = fit("lewm", "evaluated", steps=4, log_every=2, eval_every=2, eval_episodes=2, eval_plan=quick)
    assert_same_weights(weights(plain.folder / "weights.pt"), weights(evaluated.folder / "weights.pt"))
    evals = [r for r in evaluated.history if "eval/success_rate" in r]
    assert [r["step"] for r in evals] == [2, 4]
    for r in evals:
        assert r["eval/success_rate"] in (0.0, 50.0, 100.0)  # 2 episodes
        assert 0.0 <= r["eval/ci95_low"] <= r["eval/success_rate"] <= r["eval/ci95_high"] <= 100.0
    best = json.loads((evaluated.folder / "best" / "protocol.json").read_text())["best"]
    assert best["step"] == max(evals, key=lambda r: r["eval/success_rate"])["step"]
    recorded = json.loads((evaluated.folder / "protocol.json").read_text())["evaluation"]
    assert (recorded["env"], recorded["episodes"]) == ("swm/Toy-v0", 2)
    world_model_policy("evaluated/best")  # swm eval --policy wm:evaluated/best plans with it
    with pytest.raises(ConfigError, match="eval_every"):
        fit("lewm", "bad", steps=2, eval_every=0)


def test_evaluation_under_upstream_s_protocol_starts_from_the_run_s_held_out_episodes(fit, _stablewm_home, capsys):
    """``eval_protocol="upstream"``: each evaluation runs what ``swm eval --protocol upstream`` runs (goal 25
    steps on, budget 50, seed 42), from the run's validation episodes; ``eval/train_seconds`` grows with
    the steps and leaves the evaluations out."""
    from stable_worldmodel import World
    from stable_worldmodel.planning.learned import PlanSettings
    from stable_worldmodel.policy import RandomPolicy

    with World("swm/Toy-v0", 2, (16, 16), max_episode_steps=40, verbose=0) as world:  # 41-row episodes
        world.set_policy(RandomPolicy(seed=0))
        world.record_dataset("long", episodes=10, seed=0, cache_dir=_stablewm_home)
    quick = PlanSettings(samples=8, iterations=1, horizon=2, receding_horizon=2, subgoals="none")
    result = fit(
        "lewm", "proto", dataset="long", steps=4, log_every=2, eval_every=2, eval_episodes=3, eval_protocol="upstream",
        eval_plan=quick,
    )  # fmt: skip
    protocol = json.loads((result.folder / "protocol.json").read_text())
    assert protocol["evaluation"]["protocol"] == "upstream" and protocol["evaluation"]["episodes"] == 3
    evals = [r for r in result.history if "eval/success_rate" in r]
    assert [r["step"] for r in evals] == [2, 4]
    said = [line for line in capsys.readouterr().err.splitlines() if "evaluation: success" in line]
    assert [line.split(",")[0] for line in said] == ["train proto: step 2/4", "train proto: step 4/4"]
    assert said[0].endswith(f"success {evals[0]['eval/success_rate']:.1f}% [{evals[0]['eval/ci95_low']:.1f}, "
                            f"{evals[0]['eval/ci95_high']:.1f}] on 3 episodes")  # fmt: skip
    seconds = [r["eval/train_seconds"] for r in evals]
    assert 0.0 < seconds[0] < seconds[1] < result.seconds
    # loss.png gains a panel: the success rate against the step (11 inches wide at 120 dpi instead of 6)
    assert int.from_bytes((result.folder / "loss.png").read_bytes()[16:20], "big") == 11 * 120
    assert int.from_bytes((fit("lewm", "plain", steps=2).folder / "loss.png").read_bytes()[16:20], "big") == 6 * 120
    best = json.loads((result.folder / "best" / "protocol.json").read_text())["best"]
    assert best["episodes"] == 3 and len(best["starts"]) == 3
    for episode, start in best["starts"]:
        assert episode in protocol["val_episodes"] and 0 <= start < 41 - 25  # the goal lies 25 steps on
    with pytest.raises(UnknownNameError, match="Did you mean 'upstream'"):
        fit("lewm", "typo", dataset="long", steps=2, eval_every=1, eval_protocol="upstrem")


def test_a_run_records_versions_commit_command_host_and_times(fit, monkeypatch, tmp_path):
    import re
    import subprocess
    import sys

    import stable_worldmodel

    repo = tmp_path / "project"  # a research project under git, where the run is started
    repo.mkdir()
    subprocess.run(["git", "init", "-q", str(repo)], check=True)
    (repo / "train.py").write_text("print('hi')\n")
    subprocess.run(["git", "-C", str(repo), "add", "train.py"], check=True)
    subprocess.run(
        ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "x"], check=True
    )
    monkeypatch.chdir(repo)
    monkeypatch.setattr(sys, "argv", ["train.py", "--lr", "3e-4"])
    made = json.loads((fit("dummy", "prov", steps=2).folder / "protocol.json").read_text())["provenance"]
    assert made["versions"]["stable_worldmodel"] == stable_worldmodel.__version__
    assert made["versions"]["torch"] == torch.__version__
    assert made["command"] == "train.py --lr 3e-4" and made["host"]
    head = subprocess.run(["git", "-C", str(repo), "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    assert made["git"] == {"commit": head, "dirty": False}
    stamp = r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\+00:00"
    assert re.fullmatch(stamp, made["started"]) and re.fullmatch(stamp, made["ended"])
    assert made["started"] <= made["ended"]
    (repo / "train.py").write_text("print('changed')\n")
    assert json.loads((fit("dummy", "dirty", steps=2).folder / "protocol.json").read_text())["provenance"]["git"][
        "dirty"
    ]
    monkeypatch.chdir(tmp_path)  # not a repository: no git entry
    assert "git" not in json.loads((fit("dummy", "nogit", steps=2).folder / "protocol.json").read_text())["provenance"]


def test_metrics_are_mirrored_to_tensorboard(fit):
    """TensorBoard is installed with the package: every run's metrics are in ``<run>/tensorboard``."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    result = fit("dummy", "tb", steps=6, log_every=2)
    events = EventAccumulator(str(result.folder / "tensorboard"))
    events.Reload()
    logged = [(e.step, e.value) for e in events.Scalars("train/loss")]
    assert [s for s, _ in logged] == [s for s, _ in train_losses(result.folder)] == [2, 4, 6]
    assert np.allclose([v for _, v in logged], [v for _, v in train_losses(result.folder)], rtol=1e-6)
