"""``--ray-address`` where no Ray cluster answers: one ``Error:`` line naming the address and the fix,
fast, and no cluster started (``ray.init`` is replaced, so a cluster on this machine cannot interfere)."""

from __future__ import annotations

import socket
import time

import pytest

ray = pytest.importorskip("ray")

#: what ray.init(address="auto") raises when no cluster runs on this machine (Ray 2.x)
NO_CLUSTER = (
    "Could not find any running Ray instance. Please specify the one to connect to by setting "
    "`--address` flag or `RAY_ADDRESS` environment variable."
)


@pytest.fixture
def ray_init(monkeypatch):
    """``ray.init`` raising what Ray raises without a cluster; records the addresses asked for."""
    asked: list[str | None] = []

    def init(address=None, **kwargs):
        asked.append(address)
        if address:
            raise ConnectionError(NO_CLUSTER)
        raise AssertionError("a local Ray must not start in this test")

    monkeypatch.setattr(ray, "init", init)
    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    return asked


def check_line(line: str, address: str) -> None:
    for needle in (repr(address), "requires a running Ray cluster", "ray start --head", "drop --ray-address"):
        assert needle in line, line


def test_eval_ray_address_auto_without_a_cluster_is_one_error_line(swm, error_line, ray_init):
    result = swm("eval", "swm/Toy-v0", "-n", "1", "--image-size", "16", "--ray-address", "auto")
    assert result.exit_code == 1
    line = error_line(result)
    check_line(line, "auto")
    assert "Could not find any running Ray instance" in line
    assert ray_init == ["auto"]


def test_collect_ray_address_auto_without_a_cluster_is_one_error_line(swm, error_line, ray_init):
    result = swm("collect", "swm/Toy-v0", "-n", "1", "--image-size", "16", "--ray-address", "auto", "--name", "r")
    assert result.exit_code == 1
    check_line(error_line(result), "auto")


def test_a_host_port_where_nothing_listens_fails_fast_without_asking_ray(swm, error_line, ray_init):
    with socket.socket() as s:  # a port nothing listens on once closed
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"127.0.0.1:{port}"
    start = time.perf_counter()
    result = swm("eval", "swm/Toy-v0", "-n", "1", "--image-size", "16", "--ray-address", address)
    assert time.perf_counter() - start < 10  # Ray itself would wait for ever there
    assert result.exit_code == 1
    line = error_line(result)
    check_line(line, address)
    assert ray_init == []  # refused before ray.init


def test_init_ray_raises_a_config_error(ray_init):
    from stable_worldmodel.errors import ConfigError
    from stable_worldmodel.world.on_ray import init_ray

    with pytest.raises(ConfigError, match="'auto'"):
        init_ray("auto")
