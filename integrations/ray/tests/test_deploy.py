"""The Kubernetes and Slurm files (deploy/), without Kubernetes or Slurm.

The Job manifests
are valid YAML describing a Job that writes the shared variants to the volume and an Indexed
Job over big.lua's tiles that refers to them, `tile-index.sh` maps every index to the tile
`pge tiles` lists at that place, and the Slurm scripts, run as their jobs would run them,
write the same variants and tile bytes as `pge run --variants-out` and `pge run --tile
--variants`.
"""

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


def yaml_docs(name):
    with open(os.path.join(DEPLOY, "k8s", name), encoding="utf-8") as f:
        return list(yaml.safe_load_all(f))


def test_the_jobs_write_the_variants_then_every_tile_of_big_referring_to_them(pge_bin):
    claim = yaml_docs("volume.yaml")[0]
    assert claim["kind"] == "PersistentVolumeClaim"
    assert claim["spec"]["accessModes"] == ["ReadWriteMany"]
    variants = yaml_docs("variants-job.yaml")[0]
    job = yaml_docs("forest-job.yaml")[0]
    assert variants["kind"] == job["kind"] == "Job"
    spec = job["spec"]
    assert spec["completionMode"] == "Indexed"
    pod = spec["template"]["spec"]
    container = pod["containers"][0]
    env = {e["name"]: e["value"] for e in container["env"]}
    assert spec["completions"] == len(tiles(pge_bin, os.path.join(ROOT, env["SCRIPT"])))
    assert "$JOB_COMPLETION_INDEX" in container["args"][0]
    assert "--variants /world" in container["args"][0]
    writer = variants["spec"]["template"]["spec"]
    first = writer["containers"][0]
    # The same script and seed, the variants written where the tiles look for them.
    assert {e["name"]: e["value"] for e in first["env"]} == env
    assert "--variants-out /world" in first["args"][0]
    for p in (pod, writer):
        assert p["volumes"][0]["persistentVolumeClaim"]["claimName"] == claim["metadata"]["name"]
        assert p["containers"][0]["volumeMounts"][0]["mountPath"] == "/world"


def test_every_index_picks_its_tile_and_past_the_last_is_an_error(pge_bin):
    listed = tiles(pge_bin, FOREST)
    script = os.path.join(DEPLOY, "tile-index.sh")
    for k, t in enumerate(listed):
        out = subprocess.run(
            [script, FOREST, str(k)],
            env=path_env(pge_bin),
            capture_output=True,
            text=True,
            check=True,
        )
        assert out.stdout.strip() == f"{t['i']},{t['j']}"
    past = subprocess.run(
        [script, FOREST, str(len(listed))], env=path_env(pge_bin), capture_output=True, text=True
    )
    assert past.returncode == 1 and "no tile number" in past.stderr


def test_the_slurm_jobs_write_the_variants_and_a_tile_referring_to_them(pge_bin, tmp_path):
    env = path_env(pge_bin)
    env.update(SLURM_SUBMIT_DIR=ROOT, SLURM_CPUS_PER_TASK="1")
    out = tmp_path / "world"
    subprocess.run(
        ["bash", os.path.join(DEPLOY, "slurm", "variants.sbatch"), FOREST, str(out), "--seed", "4"],
        env=env,
        check=True,
        capture_output=True,
    )
    env.update(SLURM_ARRAY_TASK_ID="6")
    subprocess.run(
        ["bash", os.path.join(DEPLOY, "slurm", "forest.sbatch"), FOREST, str(out), "--seed", "4"],
        env=env,
        check=True,
        capture_output=True,
    )
    t = tiles(pge_bin, FOREST)[6]
    ref = tmp_path / "ref"
    subprocess.run(
        [pge_bin, "run", FOREST, "--variants-out", str(ref), "--seed", "4", "-q"],
        check=True,
        capture_output=True,
    )
    (ref / "tiles").mkdir()
    subprocess.run(
        [
            pge_bin,
            "run",
            FOREST,
            "--tile",
            f"{t['i']},{t['j']}",
            "--seed",
            "4",
            "--variants",
            str(ref),
            "-q",
            "-o",
            str(ref / "tiles" / "tile.glb"),
        ],
        check=True,
        capture_output=True,
    )
    assert os.listdir(out / "tiles") == [f"{t['i']}_{t['j']}.glb"]
    assert (out / "tiles" / f"{t['i']}_{t['j']}.glb").read_bytes() == (
        ref / "tiles" / "tile.glb"
    ).read_bytes()
    for name in ("variants.bin", "variants.json"):
        assert (out / name).read_bytes() == (ref / name).read_bytes()
