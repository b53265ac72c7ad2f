"""A real local Ray cluster for the cluster tests.

A head and one extra worker node, on 127.0.0.1 only, one CPU each, a small object store,
no dashboard, session files in a temporary folder; stopped at the end of the session even
when a test fails. Only the tests that ask for the ``cluster`` fixture start it.
"""

import os
import shutil
import socket
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import fakes
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
FOREST = os.path.join(HERE, "forest.lua")
OBJECT_STORE = str(80 * 1024 * 1024)


def free_ports(n: int) -> list[int]:
    """Return ``n`` distinct TCP ports nothing listens on at the moment.

    They are bound all at once, so the kernel cannot hand out one twice.
    """
    sockets = [socket.socket() for _ in range(n)]
    try:
        for s in sockets:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


def free_port() -> int:
    """Return a TCP port nothing listens on at the moment."""
    return free_ports(1)[0]


def ray_bin():
    """Return the `ray` program of this Python environment."""
    path = os.path.join(os.path.dirname(sys.executable), "ray")
    return path if os.path.exists(path) else shutil.which("ray")


NODE_PORTS = [
    "--node-manager-port",
    "--object-manager-port",
    "--metrics-export-port",
    "--dashboard-agent-listen-port",
    "--dashboard-agent-grpc-port",
    "--runtime-env-agent-port",
]


def node_ports(ports):
    """Return the flags of every port a Ray node opens, from ``ports`` (distinct, free).

    So two nodes on one machine never clash.
    """
    return [f"{flag}={port}" for flag, port in zip(NODE_PORTS, ports)]


@dataclass(frozen=True)
class Cluster:
    """The running cluster: its address, the extra node's node-manager port, the env."""

    address: str
    worker_port: int
    env: dict[str, str]


@pytest.fixture(scope="session")
def pge_bin():
    """Return the pge program under test: $PGE_BIN, else `pge` on the PATH."""
    path = os.environ.get("PGE_BIN") or shutil.which("pge")
    if not path:
        pytest.fail("no pge on the PATH: build it (cargo build --release) and add target/release")
    return os.path.abspath(path)


@pytest.fixture(scope="session")
def cluster(pge_bin):
    """Start the head and one worker node; `ray stop` at the end, whatever happened."""
    temp = tempfile.mkdtemp(prefix="pgeray", dir="/tmp")
    env = dict(os.environ)
    env["PATH"] = os.path.dirname(pge_bin) + os.pathsep + env.get("PATH", "")
    env["RAY_USAGE_STATS_ENABLED"] = "0"
    env["RAY_TMPDIR"] = temp
    ray = ray_bin()
    ports = free_ports(1 + 2 * len(NODE_PORTS))
    port = ports[0]
    head_ports = node_ports(ports[1 : 1 + len(NODE_PORTS)])
    worker_ports = node_ports(ports[1 + len(NODE_PORTS) :])
    head = [
        ray,
        "start",
        "--head",
        "--node-ip-address=127.0.0.1",
        f"--port={port}",
        "--num-cpus=1",
        f"--object-store-memory={OBJECT_STORE}",
        "--include-dashboard=false",
        "--disable-usage-stats",
        *head_ports,
    ]
    worker = [
        ray,
        "start",
        f"--address=127.0.0.1:{port}",
        "--node-ip-address=127.0.0.1",
        "--num-cpus=1",
        f"--object-store-memory={OBJECT_STORE}",
        *worker_ports,
    ]
    try:
        subprocess.run(head, env=env, check=True, capture_output=True, timeout=180)
        subprocess.run(worker, env=env, check=True, capture_output=True, timeout=180)
        manager = int(worker_ports[0].split("=")[1])
        yield Cluster(f"127.0.0.1:{port}", manager, env)
    except subprocess.CalledProcessError as e:
        pytest.fail(f"ray start failed: {e.stderr.decode(errors='replace')[-2000:]}")
    finally:
        subprocess.run([ray, "stop", "--force"], env=env, capture_output=True, timeout=120)
        shutil.rmtree(temp, ignore_errors=True)


@dataclass(frozen=True)
class FakePge:
    """The fake ``pge`` of the unit tests (fakes.py) and the log of its calls."""

    path: str
    log: Path

    def calls(self) -> list[list[str]]:
        """Return the argument lists it was called with, in order."""
        return fakes.calls(self.log)


@pytest.fixture
def fake_pge(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> FakePge:
    """Write a fake ``pge`` (no Rust build, no cluster): its path and its calls."""
    folder = tmp_path_factory.mktemp("fakepge")
    log = folder / "calls.log"
    log.touch()
    monkeypatch.setenv("FAKE_PGE_LOG", str(log))
    return FakePge(str(fakes.fake_pge(folder)), log)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Refuse a unit test that would start the cluster or need the real ``pge``."""
    for item in items:
        needs = {"cluster", "pge_bin"} & set(getattr(item, "fixturenames", ()))
        if item.get_closest_marker("unit") and needs:
            raise pytest.UsageError(f"{item.nodeid} is marked unit but uses {sorted(needs)}")
