"""The Kubernetes and Slurm files (deploy/), without Kubernetes or Slurm: the Job manifest
is valid YAML describing an Indexed Job over big.lua's tiles, `tile-index.sh` maps every
index to the tile `pge tiles` lists at that place, and the Slurm array script, run as one
array task would run it, writes the same bytes as `pge run --tile`."""

import json
import os
import subprocess

import yaml
from conftest import FOREST

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
DEPLOY = os.path.join(ROOT, "deploy")


def tiles(pge_bin, script):
    out = subprocess.run([pge_bin, "tiles", script], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def path_env(pge_bin):
    env = dict(os.environ)
    env["PATH"] = os.path.dirname(pge_bin) + os.pathsep + env.get("PATH", "")
    return env


def test_the_job_is_an_indexed_job_over_every_tile_of_big(pge_bin):
    with open(os.path.join(DEPLOY, "k8s", "forest-job.yaml"), encoding="utf-8") as f:
        docs = list(yaml.safe_load_all(f))
    job = next(d for d in docs if d["kind"] == "Job")
    claim = next(d for d in docs if d["kind"] == "PersistentVolumeClaim")
    spec = job["spec"]
    assert spec["completionMode"] == "Indexed"
    pod = spec["template"]["spec"]
    container = pod["containers"][0]
    env = {e["name"]: e["value"] for e in container["env"]}
    assert spec["completions"] == len(tiles(pge_bin, os.path.join(ROOT, env["SCRIPT"])))
    assert "$JOB_COMPLETION_INDEX" in container["args"][0]
    assert pod["volumes"][0]["persistentVolumeClaim"]["claimName"] == claim["metadata"]["name"]
    assert container["volumeMounts"][0]["mountPath"] == "/world"


def test_every_index_picks_its_tile_and_past_the_last_is_an_error(pge_bin):
    listed = tiles(pge_bin, FOREST)
    script = os.path.join(DEPLOY, "tile-index.sh")
    for k, t in enumerate(listed):
        out = subprocess.run([script, FOREST, str(k)], env=path_env(pge_bin),
                             capture_output=True, text=True, check=True)
        assert out.stdout.strip() == f"{t['i']},{t['j']}"
    past = subprocess.run([script, FOREST, str(len(listed))], env=path_env(pge_bin),
                          capture_output=True, text=True)
    assert past.returncode == 1 and "no tile number" in past.stderr


def test_a_slurm_array_task_writes_its_tile(pge_bin, tmp_path):
    env = path_env(pge_bin)
    env.update(SLURM_ARRAY_TASK_ID="6", SLURM_SUBMIT_DIR=ROOT, SLURM_CPUS_PER_TASK="1")
    out = tmp_path / "world"
    subprocess.run(["bash", os.path.join(DEPLOY, "slurm", "forest.sbatch"), FOREST, str(out),
                    "--seed", "4"], env=env, check=True, capture_output=True)
    t = tiles(pge_bin, FOREST)[6]
    ref = tmp_path / "ref.glb"
    subprocess.run([pge_bin, "run", FOREST, "--tile", f"{t['i']},{t['j']}", "--seed", "4",
                    "-q", "-o", str(ref)], check=True, capture_output=True)
    assert os.listdir(out / "tiles") == [f"{t['i']}_{t['j']}.glb"]
    assert (out / "tiles" / f"{t['i']}_{t['j']}.glb").read_bytes() == ref.read_bytes()
