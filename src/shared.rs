//! `pge run SCRIPT --variants-out DIR` writes a forest's variants once (`DIR/variants.bin`
//! and its glTF description `DIR/variants.json`); `pge run SCRIPT --tile I,J --variants DIR`
//! writes a tile that refers to them instead of carrying them (docs/glb.md, "Tiles that share
//! their variants").

use std::path::{Component, Path, PathBuf};

use anyhow::Context;
use pge_engine::ParamInfo;
use pge_engine::export::{ExportMeta, SharedVariants, variants_files};
use pge_engine::geometry::Model;
use serde_json::{Map, Value};

use crate::output::write_set;

/// The description of the shared variants in their folder.
pub const DESCRIPTION: &str = "variants.json";
/// The binary file of the shared variants in their folder.
pub const BIN: &str = "variants.bin";

/// What shared variants are grown from, as `variants.json` records it: the script's SHA-256
/// (not its path: the same script given by another path writes the same bytes), the seed,
/// and the declared parameters' values.
pub fn identity(script: &Path, meta: &ExportMeta) -> anyhow::Result<Map<String, Value>> {
    let bytes =
        std::fs::read(script).with_context(|| format!("cannot read {}", script.display()))?;
    let mut info = Map::new();
    info.insert(
        "scriptSha256".into(),
        crate::world::sha256_hex(&bytes).into(),
    );
    info.insert("seed".into(), meta.seed.into());
    let params: Map<String, Value> = meta.params.iter().cloned().collect();
    info.insert("params".into(), Value::Object(params));
    Ok(info)
}

/// Writes the variants model of a `--variants-out` run into `dir`: both files written to
/// temporaries before either takes its place (the binary file first, the description
/// last), so a failed write leaves the pair as it was.
pub fn write_variants(dir: &Path, model: &Model, info: Map<String, Value>) -> anyhow::Result<()> {
    let counts: Vec<[u64; 2]> = model
        .variant_counts
        .iter()
        .map(|c| [c.nodes, c.leaves])
        .collect();
    let (text, bin) = variants_files(model, &counts, info, BIN)?;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    write_set(&[(dir.join(BIN), &bin), (dir.join(DESCRIPTION), &text)])
}

/// What each variant of a `--variants-out` run is, in the order of the description:
/// `{"name", "vertices", "triangles", "nodes", "leaves"}` (what one instance draws and stands
/// for) and, for a variant with foliage levels of detail, `"lod": {"leaves", "roots",
/// "levels"}` (its mesh's `extras.pge.lod`; `levels = leaves - roots + 1`, from the roots
/// alone to every leaf).
pub fn summary(model: &Model) -> Vec<Value> {
    model
        .groups
        .iter()
        .enumerate()
        .map(|(g, group)| {
            let meshes = || group.meshes.iter().map(|&m| &model.meshes[m]);
            let counts = model.variant_counts.get(g).copied().unwrap_or_default();
            let mut entry = Map::new();
            entry.insert("name".into(), group.name.clone().into());
            let vertices: usize = meshes().map(|m| m.vertex_count()).sum();
            let triangles: usize = meshes().map(|m| m.triangle_count()).sum();
            entry.insert("vertices".into(), vertices.into());
            entry.insert("triangles".into(), triangles.into());
            entry.insert("nodes".into(), counts.nodes.into());
            entry.insert("leaves".into(), counts.leaves.into());
            let lod = meshes().find_map(|m| {
                let lod = m.lod.as_deref()?;
                Some((u64::from(lod.leaves()), u64::from(lod.roots())))
            });
            if let Some((leaves, roots)) = lod {
                let levels = leaves.saturating_sub(roots) + 1;
                entry.insert(
                    "lod".into(),
                    serde_json::json!({"leaves": leaves, "roots": roots, "levels": levels}),
                );
            }
            Value::Object(entry)
        })
        .collect()
}

/// The [`summary`] as lines for the terminal, one per variant.
pub fn summary_lines(summary: &[Value]) -> Vec<String> {
    summary
        .iter()
        .map(|v| {
            let n = |k: &str| v.get(k).and_then(Value::as_u64).unwrap_or(0);
            let name = v.get("name").and_then(Value::as_str).unwrap_or_default();
            let mut line = format!(
                "{name}: {} vertices, {} triangles, {} nodes, {} leaves",
                n("vertices"),
                n("triangles"),
                n("nodes"),
                n("leaves")
            );
            if let Some(lod) = v.get("lod") {
                let l = |k: &str| lod.get(k).and_then(Value::as_u64).unwrap_or(0);
                line.push_str(&format!(
                    ", {} LOD levels ({} to {} leaves)",
                    l("levels"),
                    l("roots"),
                    l("leaves")
                ));
            }
            line
        })
        .collect()
}

/// The shared variants a tile's `model` places (its instance groups without meshes of their
/// own, with at least one instance), in the model's order: `{"name", "instances", "vertices", "triangles", "nodes",
/// "leaves"}`, the last four what one instance draws and stands for (from the description);
/// and the sums over the instances of vertices, triangles, nodes and leaves (what the tile's
/// `extras.pge.stats` add for them).
pub fn referred(model: &Model, shared: &SharedVariants) -> (Vec<Value>, [u64; 4]) {
    let mut sum = [0u64; 4];
    let mut list = Vec::new();
    let placed = model
        .groups
        .iter()
        .filter(|g| g.meshes.is_empty() && !g.transforms.is_empty());
    for group in placed {
        let Some(g) = shared.group(&group.name) else {
            continue;
        };
        let n = group.transforms.len() as u64;
        let per = [g.vertices, g.triangles, g.nodes, g.leaves];
        for (s, p) in sum.iter_mut().zip(per) {
            *s = s.saturating_add(n.saturating_mul(p));
        }
        list.push(serde_json::json!({
            "name": group.name,
            "instances": n,
            "vertices": g.vertices,
            "triangles": g.triangles,
            "nodes": g.nodes,
            "leaves": g.leaves,
        }));
    }
    (list, sum)
}

/// The description in `dir`, checked against this run before it grows anything: it exists,
/// it is one, it was written for this script (same bytes) and seed, and its binary file,
/// when present, has the length it records (a tile never reads it: a worker may have the
/// description alone).
pub fn read_variants(dir: &Path, script: &Path, seed: u64) -> anyhow::Result<SharedVariants> {
    let path = dir.join(DESCRIPTION);
    let again = format!(
        "write them again with pge run {} --variants-out {}",
        script.display(),
        dir.display()
    );
    let text = std::fs::read(&path).map_err(|e| {
        anyhow::anyhow!(
            "{}: no shared variants here ({}); write them with pge run {} --variants-out {}",
            path.display(),
            e.kind(),
            script.display(),
            dir.display()
        )
    })?;
    let shared = SharedVariants::parse(&text)
        .map_err(|e| anyhow::anyhow!("{}: {e}; {again}", path.display()))?;
    let info = shared.info();
    let bytes =
        std::fs::read(script).with_context(|| format!("cannot read {}", script.display()))?;
    let recorded = |k: &str| info.get(k).cloned().unwrap_or(Value::Null);
    let other = |what: &str, was: Value| {
        anyhow::anyhow!(
            "{}: the shared variants were written for another {what} ({was}); {again}",
            path.display()
        )
    };
    if recorded("scriptSha256") != crate::world::sha256_hex(&bytes) {
        return Err(other("script", recorded("scriptSha256")));
    }
    if recorded("seed") != seed {
        return Err(other("seed", recorded("seed")));
    }
    if let Ok(meta) = std::fs::metadata(dir.join(BIN))
        && meta.len() != shared.bin_bytes()
    {
        return Err(anyhow::anyhow!(
            "{}: {} bytes where the description says {}; {again}",
            dir.join(BIN).display(),
            meta.len(),
            shared.bin_bytes()
        ));
    }
    Ok(shared)
}

/// Checks that the shared variants were written with the parameters of this run (known once
/// the script has run).
pub fn check_params(
    shared: &SharedVariants,
    dir: &Path,
    script: &Path,
    params: &[ParamInfo],
) -> anyhow::Result<()> {
    let now: Map<String, Value> = params
        .iter()
        .map(|p| (p.name.clone(), p.value.to_json()))
        .collect();
    let recorded = shared.info().get("params").cloned().unwrap_or(Value::Null);
    if recorded != Value::Object(now) {
        anyhow::bail!(
            "{}: the shared variants were written with other parameters ({recorded}); write \
             them again with pge run {} --variants-out {} and the same --set values",
            dir.join(DESCRIPTION).display(),
            script.display(),
            dir.display()
        );
    }
    Ok(())
}

/// The URI of `dir/variants.bin` relative to the folder of `output` (`../variants.bin` for a
/// tile in `DIR/tiles/`), `/`-separated and percent-encoded as glTF asks.
pub fn relative_uri(dir: &Path, output: &Path) -> anyhow::Result<String> {
    let absolute = |p: &Path| -> anyhow::Result<PathBuf> {
        let p = if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        };
        Ok(normal(&std::path::absolute(p).with_context(|| {
            format!("cannot resolve {}", p.display())
        })?))
    };
    let target = absolute(&dir.join(BIN))?;
    let from = absolute(output.parent().unwrap_or(Path::new("")))?;
    let (t, f): (Vec<_>, Vec<_>) = (target.components().collect(), from.components().collect());
    let common = t.iter().zip(&f).take_while(|(a, b)| a == b).count();
    if common == 0 {
        anyhow::bail!(
            "{} and {} have no folder in common: the tile cannot refer to the variants",
            dir.display(),
            output.display()
        );
    }
    let mut parts: Vec<String> = vec!["..".into(); f.len() - common];
    parts.extend(
        t[common..]
            .iter()
            .map(|c| encode(&c.as_os_str().to_string_lossy())),
    );
    Ok(parts.join("/"))
}

/// `p` with `.` and `..` folded (lexically).
fn normal(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// A path segment percent-encoded: everything but RFC 3986's unreserved characters.
fn encode(segment: &str) -> String {
    let mut out = String::with_capacity(segment.len());
    for b in segment.bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'-' | b'.' | b'_' | b'~') {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_uri_is_relative_to_the_tiles_folder() {
        let uri = |d: &str, o: &str| relative_uri(Path::new(d), Path::new(o)).expect("uri");
        assert_eq!(uri("/w", "/w/tiles/0_0.glb"), "../variants.bin");
        assert_eq!(uri("/w/", "/w/0_0.glb"), "variants.bin");
        assert_eq!(uri("/w/v", "/w/tiles/./a/../0_0.glb"), "../v/variants.bin");
        assert_eq!(uri("/my w/v", "/x/t.glb"), "../my%20w/v/variants.bin");
    }
}
