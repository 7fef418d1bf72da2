"""``swm demo`` end to end on the toy env with tiny settings."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from stable_worldmodel.cli.stats import SuccessSummary, wilson_interval
from stable_worldmodel.data import dataset_info, list_datasets

BASE = ("--env", "swm/Toy-v0", "--episodes", "2", "--eval-episodes", "4", "--image-size", "16", "--max-steps", "12")
#: the demo's dataset for BASE: named by what decides its content (env, episodes x max steps, seed, image size)
DATASET = "demo-toy-v0-expert-2x12-seed0-16px"
#: no training: what the tests of the collect / evaluate / plot steps need
TINY = (*BASE, "--model", "none")
#: the whole loop with a dummy world model, a few steps and a small CEM
LEARNED = (*BASE, "--model", "dummy", "--train-steps", "3", "--samples", "16", "--iterations", "2", "--num-envs", "2")


def test_demo_writes_videos_plot_results_and_one_last_line(swm, tmp_path):
    import imageio.v3 as iio

    out = tmp_path / "demo"
    result = swm("demo", *LEARNED, "--out", str(out))
    assert result.exit_code == 0, result.output
    stdout = result.stdout

    # the dataset: recorded, kept in the cache, shown
    assert list_datasets() == [DATASET]
    assert dataset_info(DATASET)["num_episodes"] == 2
    assert f"dataset '{DATASET}'" in stdout

    # one MP4 per policy, readable, at most max_steps + 1 frames
    for policy in ("random", "expert", "dummy+cem"):
        frames = iio.imread(out / f"{policy}.mp4")
        assert frames.ndim == 4 and 1 <= len(frames) <= 13
        assert frames.shape[-1] == 3
    assert not [p for p in out.iterdir() if p.is_dir()]  # no temporary folders left

    # the plot
    png = (out / "success_rates.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 5_000

    # results.json agrees with the printed table and the Wilson intervals
    results = json.loads((out / "results.json").read_text())
    assert results["env"] == "swm/Toy-v0"
    for policy, row in results["policies"].items():
        assert row["episodes"] == 4
        assert np.allclose(row["ci95"], 100 * np.asarray(wilson_interval(row["successes"], 4)), atol=1e-2)
        assert f"{row['success_rate']:.1f}%" in next(  # percent, as swm eval --json
            line for line in stdout.splitlines() if line.startswith(f"│ {policy} ")
        )
    assert results["policies"]["expert"]["successes"] == 4
    assert list(results["policies"]) == ["random", "expert", "dummy+cem"]

    # the model: trained for the steps asked, saved where the record says, planned with the CEM asked
    model = results["model"]
    assert model["run"] == "demo-dummy" and model["steps"] == 3
    assert (Path(model["checkpoint"]) / "weights.pt").is_file() and (
        Path(model["checkpoint"]) / "config.json"
    ).is_file()
    assert model["plan"]["solver"] == "cem" and model["plan"]["samples"] == 16 and model["plan"]["iterations"] == 2

    # exactly one closing line naming where the outputs are
    last = stdout.strip().splitlines()[-1]
    assert last.startswith(f"Demo outputs in {out.resolve()} ")
    for name in (
        "random.mp4",
        "expert.mp4",
        "dummy+cem.mp4",
        "success_rates.png",
        "results.json",
        DATASET,
        model["checkpoint"],
    ):
        assert name in last


def test_demo_with_a_jepa_model_also_plans_with_subgoals(swm, tmp_path):
    out = tmp_path / "demo"
    args = (*BASE, "--model", "lewm", "--train-steps", "3", "--samples", "8", "--iterations", "1", "--num-envs", "2")
    result = swm("demo", *args, "--out", str(out))
    assert result.exit_code == 0, result.output
    results = json.loads((out / "results.json").read_text())
    assert list(results["policies"]) == ["random", "expert", "lewm+cem", "lewm+cem+graph"]
    assert results["model"]["plan_graph"]["subgoals"] == "graph" and results["model"]["plan"]["subgoals"] == "none"
    assert (out / "lewm+cem+graph.mp4").is_file()


def test_demo_rerun_reuses_its_dataset_and_never_deletes_a_run(swm, tmp_path):
    from stable_worldmodel.wm.utils import checkpoint_root

    first = swm("demo", *LEARNED, "--out", str(tmp_path / "d"))
    assert first.exit_code == 0, first.output
    weights = checkpoint_root() / "demo-dummy" / "weights.pt"
    before = (weights.read_bytes(), weights.stat().st_mtime_ns)
    data = dataset_info(DATASET)
    second = swm("demo", *LEARNED, "--out", str(tmp_path / "d"))
    assert second.exit_code == 0, second.output
    assert (weights.read_bytes(), weights.stat().st_mtime_ns) == before  # the first run is untouched
    assert json.loads((tmp_path / "d" / "results.json").read_text())["model"]["run"] == "demo-dummy-2"
    assert dataset_info(DATASET) == data and list_datasets() == [DATASET]  # reused as it was
    # other settings, another dataset
    assert swm("demo", *TINY, "--seed", "1", "--out", str(tmp_path / "e")).exit_code == 0
    assert list_datasets() == sorted([DATASET, DATASET.replace("seed0", "seed1")])


def test_run_names_are_claimed_once(tmp_path):
    from stable_worldmodel.cli.demo import claim_run_name

    (tmp_path / "demo-lewm").mkdir(parents=True)
    assert [claim_run_name(tmp_path, "demo-lewm") for _ in range(2)] == ["demo-lewm-2", "demo-lewm-3"]
    assert claim_run_name(tmp_path, "demo-pldm") == "demo-pldm"


def test_a_second_demo_waits_for_the_first_recording(tmp_path):
    import os
    import select
    import subprocess
    import sys
    import time

    from stable_worldmodel.data._lock import WriterLock

    home = tmp_path / "home"
    home.mkdir()
    lock = WriterLock(home / f"{DATASET}.h5.demo").acquire()  # as a first demo recording DATASET holds it
    env = {**os.environ, "STABLEWM_HOME": str(home)}
    code = "from stable_worldmodel.cli import main; raise SystemExit(main())"
    args = [sys.executable, "-c", code, "demo", *TINY, "--out", str(tmp_path / "d")]
    proc = subprocess.Popen(args, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    seen = b""  # read from the descriptor itself: a buffered readline could hold the next lines where select won't see
    try:
        deadline = time.monotonic() + 120  # start-up may take long on a loaded machine
        while time.monotonic() < deadline and proc.poll() is None:
            if select.select([proc.stdout], [], [], 1.0)[0]:
                seen += os.read(proc.stdout.fileno(), 65536)
                if b"Waiting for another swm demo recording" in seen:
                    break
        time.sleep(0.5)
        assert proc.poll() is None and not (home / f"{DATASET}.h5").exists()  # waiting, nothing written
    finally:
        lock.release()
    out, _ = proc.communicate(timeout=120)
    assert proc.returncode == 0, (seen + out).decode(errors="replace")
    assert "Waiting for another swm demo recording" in seen.decode(errors="replace")


def test_demo_random_and_expert_share_seeds(swm, tmp_path):
    from stable_worldmodel.cli.demo import EVAL_SEED_OFFSET

    result = swm("demo", *TINY, "--seed", "3", "--out", str(tmp_path / "d"))
    assert result.exit_code == 0
    start = 3 + EVAL_SEED_OFFSET
    assert f"seeds {start}..{start + 3}" in result.stdout
    assert json.loads((tmp_path / "d" / "results.json").read_text())["eval_seeds"] == [start, start + 3]


def test_demo_bad_env_is_one_line(swm, error_line, tmp_path):
    result = swm("demo", "--env", "swm/TwoRom-v1", "--out", str(tmp_path / "d"))
    assert result.exit_code == 1
    assert "swm/TwoRoom-v2" in error_line(result)
    assert not (tmp_path / "d").exists()


def test_plot_handles_extreme_rates(tmp_path):
    from stable_worldmodel.cli.demo import plot_success_rates

    summaries = [SuccessSummary("none", 5, 0, 10.0), SuccessSummary("all", 5, 5, 3.0)]
    path = plot_success_rates(summaries, tmp_path / "p.png", "extremes")
    assert path.read_bytes().startswith(b"\x89PNG")


def test_demo_unknown_model_is_one_line_before_any_work(swm, error_line, tmp_path):
    result = swm("demo", *BASE, "--model", "lewn", "--out", str(tmp_path / "d"))
    assert result.exit_code == 1
    line = error_line(result)
    assert "'lewn'" in line and "lewm" in line
    assert not (tmp_path / "d").exists() and list_datasets() == []
