"""Reaching a cluster and naming a failed batch, without a cluster."""

from __future__ import annotations

import socket

import pytest
from conftest import free_port

from pge_world.cluster import failure, init_options, reachable
from pge_world.errors import WorldError
from pge_world.records import Tile
from pge_world.tile import TileFailed

pytestmark = pytest.mark.unit

BATCH: list[Tile] = [
    {"i": 2, "j": 1, "min": [0.0, 0.0], "max": [1.0, 1.0]},
    {"i": 3, "j": 1, "min": [1.0, 0.0], "max": [2.0, 1.0]},
]


@pytest.mark.parametrize("address", ["head", "head:port", "head:", ":"])
def test_an_address_that_is_not_host_port_is_refused(address: str) -> None:
    with pytest.raises(WorldError) as e:
        reachable(address)
    assert str(e.value) == f"--address {address} is not HOST:PORT (the head's GCS port, 6379)"


def test_nothing_listening_is_no_cluster_at_once() -> None:
    address = f"127.0.0.1:{free_port()}"
    with pytest.raises(WorldError) as e:
        reachable(address)
    message = str(e.value)
    assert message.startswith(f"no Ray cluster at {address} (")
    assert message.endswith(
        "); start one with `ray start --head` and pass its address with --address"
    )


def test_a_listening_head_is_reachable_also_as_a_ray_url() -> None:
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        port = server.getsockname()[1]
        reachable(f"127.0.0.1:{port}")
        reachable(f"ray://127.0.0.1:{port}")


def test_ray_init_is_quiet_and_a_loopback_head_is_the_drivers_node() -> None:
    assert init_options(None) == {
        "logging_level": "ERROR",
        "log_to_driver": False,
        "include_dashboard": False,
    }
    loopback = init_options("127.0.0.1:6379")
    assert loopback["address"] == "127.0.0.1:6379"
    assert loopback["_node_ip_address"] == "127.0.0.1"
    assert "_node_ip_address" not in init_options("10.0.0.5:6379")
    assert "_node_ip_address" not in init_options("auto")
    assert "include_dashboard" not in init_options("auto")


def test_a_failed_batch_is_one_line_naming_its_tile() -> None:
    error = RuntimeError("wrapped")
    own = failure(TileFailed("tile 3,1: forest.lua:12: no sap"), error, BATCH)
    assert str(own) == "tile 3,1: forest.lua:12: no sap"
    worker = failure(TileFailed("no `pge` program on the PATH of the worker"), error, BATCH)
    assert str(worker) == "tile 2,1: no `pge` program on the PATH of the worker"
    crash = failure(ValueError("Traceback...\nValueError: bad"), error, BATCH)
    assert str(crash) == "tile 2,1 failed: ValueError: bad"
    unknown = failure(None, RuntimeError("first\nthe worker died"), BATCH)
    assert str(unknown) == "tile 2,1 failed: the worker died"
