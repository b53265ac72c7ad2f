//! `pge run --stats`: one JSON object about the run and the file it wrote.

use std::path::Path;

use pge_engine::export::SharedVariants;
use pge_engine::geometry::Model;
use serde_json::Value;

/// What `--stats` reports on: the model written and how.
pub(super) struct Report<'a> {
    /// The model.
    pub(super) model: &'a Model,
    /// Seconds from the start of the run to its file written.
    pub(super) seconds: f64,
    /// The file written (the description, for shared variants).
    pub(super) output: &'a Path,
    /// The tile, if one.
    pub(super) tile: Option<(usize, usize)>,
    /// The shared variants the glb refers to, if it does.
    pub(super) shared: Option<&'a SharedVariants>,
    /// The variants written, for `--variants-out`.
    pub(super) summary: Option<Vec<Value>>,
}

impl Report<'_> {
    /// The object printed.
    pub(super) fn json(self) -> Value {
        let m = self.model;
        // A tile that refers to shared variants counts what their instances draw and stand
        // for, as its glb's extras.pge.stats do, and names them.
        let (referred, [sv, st, sn, sl]) = match self.shared {
            Some(shared) => crate::shared::referred(m, shared),
            None => (Vec::new(), [0; 4]),
        };
        let mut stats = pge::embed::model_stats(m, self.seconds);
        stats["vertices"] = (m.vertex_count() as u64 + sv).into();
        stats["triangles"] = (m.triangle_count() as u64 + st).into();
        stats["nodes"] = (m.stats.nodes + sn).into();
        stats["leaves"] = (m.stats.leaves + sl).into();
        stats["output"] = self.output.display().to_string().into();
        if let Some((i, j)) = self.tile {
            stats["tile"] = serde_json::json!([i, j]);
        }
        if self.shared.is_some() {
            stats["variants"] = referred.into();
        }
        if let Some(summary) = self.summary {
            stats["variants"] = summary.into();
        }
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use pge_engine::geometry::Mesh;

    #[test]
    fn the_report_counts_the_model_and_names_the_tile_and_file() {
        let mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("mesh");
        let model = Model::from_mesh(mesh);
        let report = Report {
            model: &model,
            seconds: 0.5,
            output: Path::new("out/0_1.glb"),
            tile: Some((0, 1)),
            shared: None,
            summary: None,
        };
        let json = report.json();
        assert_eq!(json["vertices"], 3);
        assert_eq!(json["triangles"], 1);
        assert_eq!(json["instances"], 1);
        assert_eq!(json["tile"], serde_json::json!([0, 1]));
        assert_eq!(json["output"], "out/0_1.glb");
        assert!(json.get("variants").is_none());
    }
}
