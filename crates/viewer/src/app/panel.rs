//! The viewer's side panel: terrain and GPU facts, the map inset (click to place the viewpoint), camera and colour
//! controls, live culling statistics, ground truth, build parameters with the Rebuild button, and exports.

use std::path::PathBuf;
use std::sync::Arc;

use cull::{AnyCuller, CullMethod};
use eframe::egui;
use glam::{Vec2, Vec3};
use pipeline::export::{mtl_path, to_json, write_grouped_obj_to, write_mtl_to};
use pipeline::{Grouping, QuadtreeParams};

use super::{RebuildParams, ViewMode, ViewerApp};
use crate::camera::culling_hfov_deg;
use crate::scene::ColourMode;

impl ViewerApp {
    pub(super) fn side_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("tincull");
        let t = &self.model.terrain;
        ui.label(format!(
            "{} vertices, {} triangles, {} groups, {} levels",
            t.positions.len(),
            t.num_triangles(),
            t.groups,
            t.hierarchy.as_ref().map_or(0, |_| t.max_level() + 1)
        ));
        ui.label(format!("GPU: {}", self.gpu.describe()));
        ui.separator();
        self.map_ui(ui);
        ui.separator();
        ui.horizontal(|ui| {
            ui.selectable_value(&mut self.mode, ViewMode::Eye, "Eye");
            ui.selectable_value(&mut self.mode, ViewMode::Orbit, "Orbit");
        });
        let mut eye_changed = false;
        eye_changed |= ui
            .add(egui::Slider::new(&mut self.fov_deg, 10.0..=360.0).text("field of view °"))
            .changed();
        eye_changed |= ui
            .add(egui::Slider::new(&mut self.yaw_deg, -180.0..=180.0).text("yaw °"))
            .changed();
        ui.add(egui::Slider::new(&mut self.pitch_deg, -89.0..=89.0).text("pitch °"));
        // Up to 500 m, or as high as R has raised the eye (the slider shows the true height).
        let top = self.eye_height.max(500.0);
        if ui
            .add(
                egui::Slider::new(&mut self.eye_height, 0.5..=top)
                    .logarithmic(true)
                    .text("height above ground m"),
            )
            .changed()
            && let Some(z) = self.model.ground(self.eye[0], self.eye[1])
        {
            self.eye[2] = z + self.eye_height;
            eye_changed = true;
        }
        if eye_changed {
            self.map_dirty = true;
        }
        // Decimetres; an eye given far out (`--eye 1e30,…`) in short scientific notation instead of 31 digits.
        let metres = |v: f64| {
            if v.abs() < 1e9 {
                format!("{v:.1}")
            } else {
                format!("{v:.3e}")
            }
        };
        ui.label(format!(
            "eye {}, {}, {}",
            metres(self.eye[0]),
            metres(self.eye[1]),
            metres(self.eye[2])
        ));
        ui.separator();
        ui.label("Colour");
        ui.horizontal_wrapped(|ui| {
            let has_h = self.model.terrain.hierarchy.is_some();
            ui.add_enabled_ui(has_h, |ui| {
                ui.selectable_value(&mut self.colour, ColourMode::Groups, "groups");
                ui.selectable_value(&mut self.colour, ColourMode::Level, "level");
                ui.selectable_value(&mut self.colour, ColourMode::Visibility, "visibility");
            });
            ui.selectable_value(&mut self.colour, ColourMode::Height, "height");
        });
        if self.colour == ColourMode::Level {
            let max = self.model.terrain.max_level();
            ui.add(egui::Slider::new(&mut self.level, 0..=max).text("hierarchy level"));
        }
        ui.checkbox(&mut self.culling, "cull");
        ui.checkbox(&mut self.show_orphans, "orphans (always visible)");
        ui.checkbox(&mut self.culled_wire, "culled groups as wireframe");
        ui.add_enabled_ui(self.model.terrain.hierarchy.is_some(), |ui| {
            ui.checkbox(&mut self.pvs_on, "viewcell PVS: paint what it excludes");
        });
        if self.pvs_on {
            ui.add(
                egui::Slider::new(&mut self.pvs_size, 25.0..=2000.0)
                    .logarithmic(true)
                    .text("cell side (m)"),
            );
            if let Some(p) = &self.pvs {
                let n = self.terrain().num_triangles();
                ui.label(format!(
                    "cell {:.0},{:.0}–{:.0},{:.0}, 0–{:.1} m above ground: PVS {} of {} triangles ({:.1}%), {:.2} s",
                    p.rect[0],
                    p.rect[1],
                    p.rect[2],
                    p.rect[3],
                    p.band[1],
                    p.triangles,
                    n,
                    100.0 * p.triangles as f64 / n.max(1) as f64,
                    p.seconds
                ));
            }
        }
        ui.separator();
        self.stats_ui(ui);
        ui.separator();
        self.truth_ui(ui);
        ui.separator();
        self.rebuild_ui(ui);
        ui.separator();
        self.export_ui(ui);
        if !self.status.is_empty() {
            ui.separator();
            ui.label(&self.status);
        }
    }

    pub(super) fn map_ui(&mut self, ui: &mut egui::Ui) {
        let [w, h] = self.map.renderer.size();
        let ppp = ui.ctx().pixels_per_point();
        let size = egui::vec2(w as f32 / ppp, h as f32 / ppp);
        let (rect, response) = ui.allocate_exact_size(size, egui::Sense::click());
        ui.painter().image(
            self.map.texture,
            rect,
            egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
            egui::Color32::WHITE,
        );
        let to_px = |p: Vec2| {
            let q = self.map_view.local_to_pixel(p, rect.width(), rect.height());
            rect.min + egui::vec2(q.x, q.y)
        };
        let eye = Vec3::from(self.terrain().to_local(self.eye)).truncate();
        let centre = to_px(eye);
        // The field the culler keeps (wider than the picture's once it is pitched).
        let field = culling_hfov_deg(self.fov_deg, self.pitch_deg, self.view_aspect);
        if field < 360.0 {
            let reach = self.map_view.half.length() * 0.25;
            for side in [-0.5, 0.5] {
                let a = (self.yaw_deg + side * field).to_radians() as f32;
                let tip = to_px(eye + Vec2::new(a.cos(), a.sin()) * reach);
                ui.painter()
                    .line_segment([centre, tip], egui::Stroke::new(1.5, egui::Color32::BLACK));
            }
        }
        let m = crate::palette::to_rgba8(crate::palette::MARKER_COLOUR);
        if let Some(p) = &self.pvs {
            let corner = |x: f64, y: f64| to_px(Vec3::from(self.terrain().to_local([x, y, 0.0])).truncate());
            let (a, b) = (corner(p.rect[0], p.rect[1]), corner(p.rect[2], p.rect[3]));
            ui.painter().rect_stroke(
                egui::Rect::from_two_pos(a, b),
                0.0,
                egui::Stroke::new(1.5, egui::Color32::from_rgb(m[0], m[1], m[2])),
                egui::StrokeKind::Outside,
            );
        }
        ui.painter().circle(
            centre,
            4.0,
            egui::Color32::from_rgb(m[0], m[1], m[2]),
            egui::Stroke::new(1.0, egui::Color32::BLACK),
        );
        if let Some(pos) = response.interact_pointer_pos()
            && response.clicked()
        {
            let q = pos - rect.min;
            let p = self.map_view.pixel_to_local(q.x, q.y, rect.width(), rect.height());
            let world = self.terrain().to_world([p.x, p.y, 0.0]);
            self.place_eye(world[0], world[1]);
        }
        ui.label("click the map to place the viewpoint");
    }

    pub(super) fn stats_ui(&mut self, ui: &mut egui::Ui) {
        let s = self.list.stats;
        let n = self.terrain().num_triangles();
        if let Some(culler) = &self.model.culler {
            let current = culler.method();
            let mut chosen = current;
            egui::ComboBox::from_label("culling method")
                .selected_text(current.name())
                .show_ui(ui, |ui| {
                    // Only the methods that apply to the hierarchy (`thesis` needs crystals, `stewart` a quadtree).
                    let hierarchy = self.model.terrain.hierarchy.as_ref();
                    for m in cull::CullMethod::ALL {
                        if hierarchy.is_none_or(|h| m.check(h).is_ok()) {
                            ui.selectable_value(&mut chosen, m, m.name());
                        }
                    }
                });
            if chosen != current {
                self.model.set_method(chosen);
            }
            if matches!(current, CullMethod::Safe | CullMethod::LloydEgbert) {
                self.culler_params_ui(ui, current);
            }
            ui.label(format!(
                "nodes tested {}, culled {} (occlusion {}, frustum {}), skipped {}",
                s.nodes_tested,
                s.culled_by_occlusion + s.culled_by_frustum,
                s.culled_by_occlusion,
                s.culled_by_frustum,
                s.nodes_skipped
            ));
            ui.label(format!(
                "triangles drawn {} of {} ({:.1}%), {} ranges",
                s.triangles_drawn,
                n,
                100.0 * f64::from(s.triangles_drawn) / n.max(1) as f64,
                self.list.ranges.len()
            ));
            if current == CullMethod::Safe {
                let budget = self.model.safe.work_budget;
                ui.label(format!(
                    "work {} units of {}, {} occluder edges written",
                    s.work,
                    if budget == usize::MAX {
                        "no limit".to_string()
                    } else {
                        budget.to_string()
                    },
                    s.occluder_edges
                ));
            }
            ui.label(format!("cull {:.1} µs", self.cull_us.0.unwrap_or(0.0)));
            if let Some(AnyCuller::LloydEgbert(le)) = &self.model.culler {
                ui.checkbox(&mut self.show_horizon, "horizon buffer");
                if self.show_horizon {
                    let profile = le.horizon_after(&self.camera()).profile();
                    let field = culling_hfov_deg(self.fov_deg, self.pitch_deg, self.view_aspect);
                    let view = (field < 360.0).then_some((self.yaw_deg, field));
                    horizon_plot(ui, &profile, view);
                }
            }
        } else {
            ui.label("no hierarchy: Rebuild to cull");
        }
        ui.label(format!(
            "frame {:.2} ms culled, {:.2} ms everything",
            self.ms_culled.0.unwrap_or(f64::NAN),
            self.ms_all.0.unwrap_or(f64::NAN)
        ));
    }

    /// The horizon cullers' run-time parameters, as `tincull cull`'s flags: the columns per face for both, the patch,
    /// work budget and coarse columns for `safe`. The culler takes them when a control is let go (preparing it again
    /// takes a moment on a large terrain, too long for every step of a drag).
    fn culler_params_ui(&mut self, ui: &mut egui::Ui, method: CullMethod) {
        let p = &mut self.safe_edit;
        let mut let_go = false;
        let mut watch = |r: egui::Response| let_go |= r.drag_stopped() || (r.changed() && !r.dragged());
        egui::ComboBox::from_label("horizon columns per face")
            .selected_text(p.columns_per_face.to_string())
            .show_ui(ui, |ui| {
                for n in (2..=12).map(|k| 1usize << k) {
                    watch(ui.selectable_value(&mut p.columns_per_face, n, n.to_string()));
                }
            });
        if method == CullMethod::Safe {
            watch(ui.add(egui::Slider::new(&mut p.patch, 1..=cull::MAX_PATCH).text("patch (triangles)")));
            watch(
                ui.add(
                    egui::Slider::new(&mut p.work_budget, 100..=2_000_000)
                        .clamping(egui::SliderClamping::Edits)
                        .logarithmic(true)
                        .text("work budget (units)"),
                ),
            );
            watch(
                ui.add(
                    egui::Slider::new(&mut p.coarse_columns, 0..=64)
                        .clamping(egui::SliderClamping::Edits)
                        .text("coarse columns (0: off)"),
                ),
            );
        }
        if let_go && *p != self.model.safe && p.check().is_ok() {
            self.model.set_safe(*p);
        }
    }

    pub(super) fn truth_ui(&mut self, ui: &mut egui::Ui) {
        let busy = self.truth_job.is_some();
        let can = self.model.culler.is_some() && !busy;
        if ui
            .add_enabled(can, egui::Button::new("Ground truth here (false culls in red)"))
            .clicked()
        {
            self.start_truth(ui.ctx());
        }
        if busy {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("computing ground truth…");
            });
        }
        if let Some(t) = &self.truth {
            let e = t.camera.position;
            ui.label(format!(
                "{} visible triangles, {} false culls at {:.0}, {:.0}, {:.0}",
                t.visible, t.count, e[0], e[1], e[2]
            ));
        }
    }

    pub(super) fn rebuild_ui(&mut self, ui: &mut egui::Ui) {
        ui.label("Build parameters");
        let RebuildParams {
            build: p,
            without_regions,
        } = &mut self.params;
        egui::Grid::new("params").num_columns(2).show(ui, |ui| {
            ui.label("grouping");
            let mut quadtree = matches!(p.grouping, Grouping::Quadtree(_));
            ui.horizontal(|ui| {
                ui.radio_value(&mut quadtree, false, "crystal");
                ui.radio_value(&mut quadtree, true, "quadtree");
            });
            ui.end_row();
            match (&p.grouping, quadtree) {
                (Grouping::Crystal, true) => p.grouping = Grouping::Quadtree(QuadtreeParams::default()),
                (Grouping::Quadtree(_), false) => {
                    // Crystal groups grow from the regions.
                    p.grouping = Grouping::Crystal;
                    *without_regions = false;
                }
                _ => {}
            }
            if let Grouping::Quadtree(q) = &mut p.grouping {
                ui.label("finest depth (0 = auto)");
                let mut depth = q.depth.unwrap_or(0);
                if ui
                    .add(
                        egui::DragValue::new(&mut depth)
                            .range(0..=16)
                            .clamp_existing_to_range(false),
                    )
                    .changed()
                {
                    q.depth = (depth > 0).then_some(depth);
                    q.cell = None;
                }
                ui.end_row();
                if let Some(cell) = q.cell {
                    // From --cell-size: it sets the finest level until a depth is chosen.
                    ui.label("finest cell");
                    ui.label(format!("{} m", tin::compact_number(cell)));
                    ui.end_row();
                }
                ui.label("regions");
                let mut regions = !*without_regions;
                ui.checkbox(&mut regions, "horizons and regions")
                    .on_hover_text("off: the cells alone, for the safe and lloyd-egbert cullers (much faster)");
                *without_regions = !regions;
                ui.end_row();
            }
            if !*without_regions {
                ui.label("sectors");
                ui.add(
                    egui::DragValue::new(&mut p.sectors)
                        .range(4..=1024)
                        .clamp_existing_to_range(false),
                );
                ui.end_row();
                ui.label("subsectors");
                ui.add(
                    egui::DragValue::new(&mut p.subsectors)
                        .range(1..=256)
                        .clamp_existing_to_range(false),
                );
                ui.end_row();
            }
            if matches!(p.grouping, Grouping::Crystal) {
                ui.label("seeds (0 = default)");
                let mut seeds = p.crystal.seeds.unwrap_or(0);
                if ui
                    .add(
                        egui::DragValue::new(&mut seeds)
                            .range(0..=1_000_000)
                            .clamp_existing_to_range(false),
                    )
                    .changed()
                {
                    p.crystal.seeds = (seeds > 0).then_some(seeds);
                }
                ui.end_row();
                ui.label("orphan passes");
                ui.add(
                    egui::DragValue::new(&mut p.crystal.orphan_passes)
                        .range(0..=100)
                        .clamp_existing_to_range(false),
                );
                ui.end_row();
                ui.label("min group");
                ui.add(
                    egui::DragValue::new(&mut p.crystal.min_group)
                        .range(1..=100_000)
                        .clamp_existing_to_range(false),
                );
                ui.end_row();
                ui.label("max expanse");
                ui.add(
                    egui::DragValue::new(&mut p.crystal.max_expanse)
                        .range(0.001..=1.0)
                        .clamp_existing_to_range(false)
                        .speed(0.005),
                );
                ui.end_row();
                ui.label("rng seed");
                ui.add(egui::DragValue::new(&mut p.crystal.rng_seed));
                ui.end_row();
            }
        });
        match &self.rebuild_job {
            Some(job) => {
                let (stage, done, total) = job.progress.lock().map(|g| g.clone()).unwrap_or_default();
                let f = if total > 0 { done as f32 / total as f32 } else { 0.0 };
                ui.add(egui::ProgressBar::new(f).text(format!(
                    "{stage} {done}/{total} ({:.0} s)",
                    job.started.elapsed().as_secs_f64()
                )));
            }
            None => {
                if ui.button("Rebuild").clicked() {
                    let rebuild = Arc::clone(&self.rebuild);
                    self.start_rebuild(ui.ctx(), rebuild);
                }
            }
        }
    }

    pub(super) fn export_ui(&mut self, ui: &mut egui::Ui) {
        ui.label("Export (path without extension)");
        ui.text_edit_singleline(&mut self.export_stem);
        let Some(h) = self.model.terrain.hierarchy.as_ref() else {
            ui.label("(no hierarchy to export)");
            return;
        };
        let stem = PathBuf::from(&self.export_stem);
        let mut result: Option<std::result::Result<PathBuf, String>> = None;
        let inputs = &self.inputs;
        ui.horizontal(|ui| {
            if ui.button(".tch").clicked() {
                let path = stem.with_extension("tch");
                let written = h.to_bytes().map_err(|e| e.to_string());
                let written = written.and_then(|b| write_export(inputs, &path, |w| w.write_all(&b)));
                result = Some(written.map(|_| path));
            }
            if ui.button("JSON").clicked() {
                let path = stem.with_extension("json");
                let written = to_json(h).map_err(|e| format!("{e:#}"));
                let written = written.and_then(|t| write_export(inputs, &path, |w| w.write_all(t.as_bytes())));
                result = Some(written.map(|_| path));
            }
            if ui.button("grouped OBJ").clicked() {
                let path = stem.with_extension("obj");
                let written = write_grouped_obj(inputs, h, &path);
                result = Some(written.map(|_| path));
            }
        });
        match result {
            Some(Ok(path)) => self.status = format!("wrote {}", path.display()),
            Some(Err(e)) => self.status = format!("export failed: {e}"),
            None => {}
        }
    }
}

/// A batch of export files that may replace none of `inputs` (the terrain shown and the files read beside it).
fn export_batch(inputs: &[PathBuf]) -> std::result::Result<outfile::Batch, String> {
    let mut batch = outfile::Batch::new();
    for input in inputs {
        batch.input(input).map_err(|e| e.to_string())?;
    }
    Ok(batch)
}

/// Writes one export file, `write` giving its content, unless it is one of `inputs`.
fn write_export(
    inputs: &[PathBuf],
    path: &std::path::Path,
    write: impl FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>,
) -> std::result::Result<(), String> {
    let mut batch = export_batch(inputs)?;
    batch.add(path, write).map_err(|e| e.to_string())?;
    batch.commit().map_err(|e| e.to_string())
}

/// Writes the grouped OBJ of `h` and its `.mtl` beside it, both or neither, unless one is one of `inputs`.
fn write_grouped_obj(
    inputs: &[PathBuf],
    h: &cull::Hierarchy,
    obj: &std::path::Path,
) -> std::result::Result<(), String> {
    let (mtl, name) = mtl_path(obj).map_err(|e| format!("{e:#}"))?;
    let mut batch = export_batch(inputs)?;
    batch.add(&mtl, |w| write_mtl_to(h, w)).map_err(|e| e.to_string())?;
    batch
        .add(obj, |w| write_grouped_obj_to(h, &name, w))
        .map_err(|e| e.to_string())?;
    batch.commit().map_err(|e| e.to_string())
}

/// Plots a horizon buffer (azimuth 0–360° across, elevation up; uncovered columns left out) with the view's edges
/// when it is narrower than 360° (`(yaw, fov)` in degrees).
fn horizon_plot(ui: &mut egui::Ui, profile: &[(f64, Option<f64>)], view: Option<(f64, f64)>) {
    let size = egui::vec2(ui.available_width(), 90.0);
    let (rect, _) = ui.allocate_exact_size(size, egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, egui::Color32::from_gray(245));
    let (lo, hi) = profile
        .iter()
        .filter_map(|p| p.1)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), e| (lo.min(e), hi.max(e)));
    if lo > hi {
        painter.text(
            rect.center(),
            egui::Align2::CENTER_CENTER,
            "horizon buffer empty",
            egui::FontId::proportional(12.0),
            egui::Color32::DARK_GRAY,
        );
        return;
    }
    let pad = ((hi - lo) * 0.1).max(0.5);
    let (lo, hi) = (lo - pad, hi + pad);
    let x = |azimuth: f64| rect.left() + (azimuth / 360.0) as f32 * rect.width();
    let y = |elevation: f64| rect.bottom() - ((elevation - lo) / (hi - lo)) as f32 * rect.height();
    let stroke = egui::Stroke::new(1.0, egui::Color32::from_rgb(40, 90, 200));
    for pair in profile.windows(2) {
        if let ((a0, Some(e0)), (a1, Some(e1))) = (pair[0], pair[1]) {
            painter.line_segment([egui::pos2(x(a0), y(e0)), egui::pos2(x(a1), y(e1))], stroke);
        }
    }
    if let Some((yaw, fov)) = view {
        for edge in [yaw - fov / 2.0, yaw + fov / 2.0] {
            let a = x(edge.rem_euclid(360.0));
            painter.line_segment(
                [egui::pos2(a, rect.top()), egui::pos2(a, rect.bottom())],
                egui::Stroke::new(1.0, egui::Color32::BLACK),
            );
        }
    }
    painter.text(
        rect.left_top() + egui::vec2(3.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("{hi:.1}°"),
        egui::FontId::proportional(10.0),
        egui::Color32::DARK_GRAY,
    );
    painter.text(
        rect.left_bottom() + egui::vec2(3.0, -2.0),
        egui::Align2::LEFT_BOTTOM,
        format!("{lo:.1}°"),
        egui::FontId::proportional(10.0),
        egui::Color32::DARK_GRAY,
    );
}
