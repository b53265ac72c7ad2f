//! The side panel: the script's parameters, seed and steps, view toggles and levels of
//! detail, statistics, export.

use std::path::{Path, PathBuf};

use eframe::egui::{self, RichText};
use pge_engine::{ParamInfo, ParamValue};

use super::{ERROR_COLOR, PreviewApp, gone_message};
use crate::reload::{Generation, Status};

impl PreviewApp {
    pub(super) fn side_panel(&mut self, ui: &mut egui::Ui) {
        let script = self.live.reloader().script().to_path_buf();
        ui.heading(
            script
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        );
        self.status_line(ui);
        ui.separator();
        egui::ScrollArea::vertical().show(ui, |ui| {
            egui::CollapsingHeader::new("Parameters")
                .default_open(true)
                .show(ui, |ui| self.params_ui(ui));
            egui::CollapsingHeader::new("Seed and steps")
                .default_open(true)
                .show(ui, |ui| self.seed_ui(ui));
            egui::CollapsingHeader::new("View")
                .default_open(true)
                .show(ui, |ui| self.view_ui(ui));
            egui::CollapsingHeader::new("Statistics")
                .default_open(true)
                .show(ui, |ui| self.stats_ui(ui));
            egui::CollapsingHeader::new("Export")
                .default_open(false)
                .show(ui, |ui| self.export_ui(ui));
        });
    }

    fn status_line(&self, ui: &mut egui::Ui) {
        match self.live.reloader().status() {
            Status::Running => {
                let secs = self
                    .live
                    .reloader()
                    .running_since()
                    .map_or(0.0, |t| t.elapsed().as_secs_f64());
                ui.horizontal(|ui| {
                    ui.spinner();
                    ui.label(format!("generating… {secs:.1} s"));
                });
            }
            Status::Ready => {
                let secs = self.live.reloader().current().map_or(0.0, |g| g.seconds);
                ui.label(format!("up to date (generated in {secs:.2} s)"));
            }
            Status::Error(message) => {
                ui.label(RichText::new(message).color(ERROR_COLOR).monospace());
            }
            Status::Gone => {
                ui.label(
                    RichText::new(gone_message(self.live.reloader().script())).color(ERROR_COLOR),
                );
            }
        }
        if self.live.reloader().is_running()
            && !matches!(self.live.reloader().status(), Status::Running)
        {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("generating…");
            });
        }
        if let Some(e) = self.live.watch_error() {
            ui.label(RichText::new(e).color(ERROR_COLOR));
        }
    }

    fn params_ui(&mut self, ui: &mut egui::Ui) {
        let params: Vec<ParamInfo> = self
            .live
            .reloader()
            .current()
            .map(|g| g.params.clone())
            .unwrap_or_default();
        if params.is_empty() {
            ui.label("The script declares no parameters (pge.params).");
            return;
        }
        let mut changed: Vec<(String, ParamValue)> = Vec::new();
        egui::Grid::new("params")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                for p in &params {
                    let value = self
                        .edits
                        .get(&p.name)
                        .cloned()
                        .unwrap_or_else(|| p.value.clone());
                    let label = ui.label(&p.name);
                    if let Some(doc) = &p.doc {
                        label.on_hover_text(doc);
                    }
                    if let Some(v) = self.param_widget(ui, p, value) {
                        changed.push((p.name.clone(), v));
                    }
                    ui.end_row();
                }
            });
        if ui.button("Reset to defaults").clicked() {
            self.edits.clear();
            self.text_edits.clear();
            let mut s = self.live.reloader().settings().clone();
            s.params.clear();
            self.settings_changed(s);
        }
        if !changed.is_empty() {
            let mut s = self.live.reloader().settings().clone();
            for (name, v) in changed {
                s.set_param(&name, v.to_string());
                self.edits.insert(name, v);
            }
            self.settings_changed(s);
        }
    }

    fn param_widget(
        &mut self,
        ui: &mut egui::Ui,
        p: &ParamInfo,
        value: ParamValue,
    ) -> Option<ParamValue> {
        let range = p.min.zip(p.max).filter(|(a, b)| a < b);
        match value {
            ParamValue::Integer(mut i) => {
                let r = match range {
                    Some((a, b)) => ui.add(egui::Slider::new(
                        &mut i,
                        a.ceil() as i64..=b.floor() as i64,
                    )),
                    None => ui.add(egui::DragValue::new(&mut i)),
                };
                r.changed().then_some(ParamValue::Integer(i))
            }
            ParamValue::Number(mut n) => {
                let r = match range {
                    Some((a, b)) => ui.add(egui::Slider::new(&mut n, a..=b)),
                    None => {
                        let speed = 0.01 * n.abs().max(0.1);
                        ui.add(egui::DragValue::new(&mut n).speed(speed))
                    }
                };
                r.changed().then_some(ParamValue::Number(n))
            }
            ParamValue::Bool(mut b) => ui
                .checkbox(&mut b, "")
                .changed()
                .then_some(ParamValue::Bool(b)),
            ParamValue::Text(s) => {
                let text = self
                    .text_edits
                    .entry(p.name.clone())
                    .or_insert_with(|| s.clone());
                let r = ui.text_edit_singleline(text);
                (r.lost_focus() && *text != s).then(|| ParamValue::Text(text.clone()))
            }
        }
    }

    fn seed_ui(&mut self, ui: &mut egui::Ui) {
        let mut s = self.live.reloader().settings().clone();
        ui.horizontal(|ui| {
            ui.label("seed");
            ui.add(egui::DragValue::new(&mut s.seed));
            if ui.button("new seed").clicked() {
                s.seed = new_seed(s.seed);
            }
        });
        if let Some(total) = self.total_steps.filter(|t| *t > 1) {
            let mut k = s.steps.unwrap_or(total).min(total);
            ui.horizontal(|ui| {
                ui.label("step");
                if ui.add(egui::Slider::new(&mut k, 0..=total)).changed() {
                    s.steps = if k >= total { None } else { Some(k) };
                }
            });
            ui.horizontal(|ui| {
                if ui.button("⏮").on_hover_text("first step").clicked() {
                    s.steps = Some(0);
                }
                if ui.button("◀").on_hover_text("one step back").clicked() {
                    s.steps = Some(k.saturating_sub(1));
                }
                if ui.button("▶").on_hover_text("one step forward").clicked() {
                    s.steps = if k + 1 >= total { None } else { Some(k + 1) };
                }
                if ui.button("⏭").on_hover_text("to the end").clicked() {
                    s.steps = None;
                }
                let label = if self.playing {
                    "⏸ pause"
                } else {
                    "⏵ play"
                };
                if ui
                    .button(label)
                    .on_hover_text("grow step by step")
                    .clicked()
                {
                    self.playing = !self.playing;
                    if self.playing && s.steps.is_none() {
                        s.steps = Some(0);
                    }
                }
            });
        } else {
            ui.label("Step-wise algorithms get a step scrubber here.");
        }
        if s != *self.live.reloader().settings() {
            self.settings_changed(s);
        }
    }

    fn view_ui(&mut self, ui: &mut egui::Ui) {
        let before = (self.toggles, self.turntable);
        ui.checkbox(&mut self.toggles.wireframe, "wireframe (W)");
        ui.checkbox(&mut self.toggles.skeleton, "skeleton (K)");
        ui.checkbox(&mut self.toggles.leaves, "leaves (L)");
        ui.checkbox(&mut self.toggles.grid, "ground grid (G)");
        self.lod_ui(ui);
        ui.checkbox(&mut self.turntable, "turntable (T)");
        if ui.button("Frame the model (F)").clicked() {
            self.frame_model();
        }
        ui.label(
            RichText::new("drag: orbit · right/middle drag or shift: pan · wheel: zoom").small(),
        );
        if before != (self.toggles, self.turntable) {
            self.viewport_dirty = true;
        }
    }

    pub(super) fn frame_model(&mut self) {
        if let Some(b) = self.live.reloader().current().and_then(|g| g.scene.bounds) {
            self.camera.frame(b);
            self.viewport_dirty = true;
        }
    }

    /// The leaf level slider, for a model with levels of detail: redraws through the two
    /// ranges of V of each sector, the geometry stays on the GPU.
    fn lod_ui(&mut self, ui: &mut egui::Ui) {
        let forest = self
            .live
            .reloader()
            .current()
            .is_some_and(|g| g.scene.meshes.iter().any(|m| m.forest));
        if forest {
            self.forest_ui(ui);
        }
        let Some(g) = self.live.reloader().current() else {
            return;
        };

        let lods: Vec<_> = g
            .scene
            .meshes
            .iter()
            .filter(|m| !m.forest)
            .filter_map(|m| m.lod.as_ref())
            .collect();
        if lods.is_empty() {
            return;
        }
        ui.add(
            egui::Slider::new(&mut self.toggles.lod_percent, 1..=100)
                .suffix("%")
                .text("leaf level"),
        );
        let drawn: u32 = lods.iter().map(|l| l.drawn(self.toggles.lod_percent)).sum();
        ui.label(RichText::new(format!("{drawn} leaves drawn")).small());
        ui.checkbox(&mut self.toggles.lod_colors, "colour leaves by level");
    }

    /// The leaf budget slider of a forest: the most leaves its trees draw in a frame (as
    /// many triangles again go to bark); redraws through the bands of V, the geometry stays
    /// on the GPU.
    fn forest_ui(&mut self, ui: &mut egui::Ui) {
        ui.add(
            egui::Slider::new(&mut self.toggles.leaf_budget, crate::forest::LEAF_BUDGETS)
                .logarithmic(true)
                .text("leaf budget"),
        )
        .on_hover_text(
            "forest: the most leaves drawn in a frame, nearer trees finer; \
             as many triangles again for bark; a 128th of it while the camera moves",
        );
        if let Some(r) = &self.renderer {
            ui.label(RichText::new(format!("{} leaves drawn", r.forest_leaves())).small());
        }
        ui.checkbox(&mut self.toggles.lod_colors, "colour leaves by level");
    }

    fn stats_ui(&mut self, ui: &mut egui::Ui) {
        let Some(g) = self.live.reloader().current() else {
            ui.label("no model yet");
            return;
        };
        let s = &g.scene.stats;
        egui::Grid::new("stats").num_columns(2).show(ui, |ui| {
            let mut row = |k: &str, v: String| {
                ui.label(k);
                ui.label(v);
                ui.end_row();
            };
            row("vertices", s.vertices.to_string());
            row("triangles", s.triangles.to_string());
            if let Some(r) = &self.renderer {
                row("drawn now", format!("{} triangles", r.triangles()));
            }
            row("nodes", s.nodes.to_string());
            row("leaves", s.leaves.to_string());
            if s.modules > 0 {
                row("modules", s.modules.to_string());
            }
            let steps = if g.finished {
                g.steps_taken.to_string()
            } else {
                format!("{} (stopped early)", g.steps_taken)
            };
            row("steps", steps);
            for (phase, secs) in &s.phases {
                row(&format!("⏱ {phase}"), format!("{:.1} ms", secs * 1000.0));
            }
            row("generation", format!("{:.1} ms", g.seconds * 1000.0));
            if let Some(l) = self.live.reloader().last_latency() {
                row(
                    "save → model",
                    format!("{:.0} ms", l.as_secs_f64() * 1000.0),
                );
            }
            if let Some(l) = self.save_to_screen {
                row(
                    "save → screen",
                    format!("{:.0} ms", l.as_secs_f64() * 1000.0),
                );
            }
            row("draw", format!("{:.1} ms", self.render_ms));
            row("frames/s", format!("{:.0}", self.fps()));
        });
    }

    fn export_ui(&mut self, ui: &mut egui::Ui) {
        let Some(write) = self.export else {
            ui.label("no export in this window");
            return;
        };
        ui.text_edit_singleline(&mut self.export_path);
        ui.horizontal(|ui| {
            let stem = PathBuf::from(&self.export_path);
            if ui.button("Export .glb").clicked() {
                let path = stem.with_extension("glb");
                self.export_path = path.to_string_lossy().into_owned();
                self.export_message = self
                    .live
                    .reloader()
                    .current()
                    .map(|g| export(write, g, &path));
            }
            if ui.button("Export .obj").clicked() {
                let path = stem.with_extension("obj");
                self.export_path = path.to_string_lossy().into_owned();
                self.export_message = self
                    .live
                    .reloader()
                    .current()
                    .map(|g| export(write, g, &path));
            }
        });
        match &self.export_message {
            Some(Ok(m)) => {
                ui.label(m);
            }
            Some(Err(m)) => {
                ui.label(RichText::new(m).color(ERROR_COLOR));
            }
            None => {}
        }
    }
}

/// A seed different from `old`, from the clock.
fn new_seed(old: u64) -> u64 {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos() as u64);
    let seed = (nanos ^ old.rotate_left(17)) % 1_000_000;
    if seed == old { seed + 1 } else { seed }
}

/// Writes the generation's model to `path` with `write` (the host's writer: `pge preview`
/// writes `.glb`, or `.obj` with its `.mtl` and textures, exactly as `pge run` does).
fn export(write: crate::ExportFn, g: &Generation, path: &Path) -> Result<String, String> {
    write(&g.model, g.settings.seed, &g.params, path).map_err(|e| format!("{e:#}"))?;
    Ok(format!("wrote {}", path.display()))
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::Vec3;
    use pge_engine::geometry::{Mesh, Model};

    use super::*;
    use crate::reload::Settings;
    use crate::scene::Scene;

    fn generation() -> Generation {
        let mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
        let model = Model::from_mesh(mesh);
        Generation {
            scene: Arc::new(Scene::new(&model)),
            model: Arc::new(model),
            params: Vec::new(),
            loaded: Vec::new(),
            steps_taken: 1,
            finished: true,
            seconds: 0.0,
            settings: Settings {
                seed: 7,
                ..Settings::default()
            },
        }
    }

    /// A writer of the glb alone, with the seed in its metadata.
    fn glb_writer(model: &Model, seed: u64, _: &[ParamInfo], path: &Path) -> anyhow::Result<()> {
        let meta = pge_engine::export::ExportMeta {
            seed,
            params: Vec::new(),
        };
        std::fs::write(path, pge_engine::export::glb_bytes(model, &meta)?)?;
        Ok(())
    }

    #[test]
    fn the_export_writes_with_the_hosts_writer_and_reports_its_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        let g = generation();
        let glb = dir.path().join("tree.glb");
        assert!(
            export(glb_writer, &g, &glb)
                .expect("glb")
                .contains("tree.glb")
        );
        assert_eq!(&std::fs::read(&glb).expect("written")[0..4], b"glTF");
        let missing = dir.path().join("missing/tree.glb");
        let err = export(glb_writer, &g, &missing).expect_err("no such folder");
        assert!(err.contains("No such file"), "{err}");
    }

    #[test]
    fn new_seeds_differ_from_the_old_one() {
        for old in [0, 1, 999_999, u64::MAX] {
            assert_ne!(new_seed(old), old);
        }
    }
}
