//! Background work of the viewer: the rebuild (the pipeline, or a test's stand-in) and the ground truth for a
//! viewpoint run in threads; the UI polls their channels each frame and stays responsive meanwhile. Also the
//! startup actions that press those buttons by themselves.

use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use cull::Camera;
use eframe::egui;
use glam::DVec3;

use super::{Model, Progress, RebuildFn, ViewerApp};
use crate::scene::{ColourMode, GpuScene};

pub(super) struct RebuildJob {
    pub(super) progress: Arc<Mutex<(String, u64, u64)>>,
    pub(super) result: Receiver<std::result::Result<Model, String>>,
    pub(super) started: Instant,
}

pub(super) struct TruthJob {
    pub(super) camera: Camera,
    pub(super) drawn_fingerprint: u64,
    pub(super) drawn: Vec<bool>,
    pub(super) result: Receiver<Vec<bool>>,
}

/// The ground truth of one view, compared with what the culler drew for it: shown while the camera and the drawn
/// set stay as they were (another eye, yaw, field of view, method or culler parameter clears it).
pub(super) struct Truth {
    pub(super) camera: Camera,
    pub(super) drawn_fingerprint: u64,
    pub(super) visible: usize,
    pub(super) false_culls: Vec<bool>,
    pub(super) count: usize,
}

impl Truth {
    /// Whether the truth still describes the view: the same camera (eye, yaw, field of view) and the same drawn set.
    pub(super) fn holds_for(&self, camera: &Camera, drawn_fingerprint: u64) -> bool {
        self.camera == *camera && self.drawn_fingerprint == drawn_fingerprint
    }
}

impl ViewerApp {
    /// Computes the ground truth for the current viewpoint in a background thread.
    pub(super) fn start_truth(&mut self, ctx: &egui::Context) {
        if self.truth_job.is_some() || self.model.culler.is_none() {
            return;
        }
        let (tx, rx) = channel();
        let tin = Arc::clone(&self.model.tin);
        let locator = Arc::clone(&self.model.locator);
        let camera = self.camera();
        let ctx = ctx.clone();
        std::thread::spawn(move || {
            let eye = DVec3::from_array(camera.position);
            let mut visible = truth::GroundTruth::with_locator(&tin, &locator).visible_triangles(eye);
            // A view narrower than 360° sees only its wedge: what lies outside it is culled by the view, not hidden
            // wrongly (as `eval --fov` scores it).
            if camera.hfov > 0.0 && camera.hfov < std::f64::consts::TAU {
                let view = truth::in_view(&tin, eye, camera.yaw, 0.5 * camera.hfov);
                visible.iter_mut().zip(view).for_each(|(v, inside)| *v &= inside);
            }
            let _ = tx.send(visible);
            ctx.request_repaint();
        });
        let n = self.terrain().num_triangles();
        self.truth_job = Some(TruthJob {
            camera,
            drawn_fingerprint: self.drawn_fingerprint,
            drawn: self.list.mask(n),
            result: rx,
        });
    }

    /// Rebuilds the hierarchy with the panel's parameters in a background thread, with progress.
    pub(super) fn start_rebuild(&mut self, ctx: &egui::Context, rebuild: RebuildFn) {
        if self.rebuild_job.is_some() {
            return;
        }
        let progress = Arc::new(Mutex::new(("starting".to_string(), 0u64, 0u64)));
        let (tx, rx) = channel();
        let tin = Arc::clone(&self.model.tin);
        let params = self.params.clone();
        let method = self.model.method;
        let safe = self.model.safe;
        let ctx = ctx.clone();
        let shared = Arc::clone(&progress);
        let repaint = ctx.clone();
        let report: Progress = Arc::new(move |stage: &str, done: u64, total: u64| {
            if let Ok(mut g) = shared.lock() {
                *g = (stage.to_string(), done, total);
            }
            repaint.request_repaint();
        });
        std::thread::spawn(move || {
            let result = rebuild(&tin, &params, report)
                .map_err(|e| e.to_string())
                .and_then(|h| Model::from_hierarchy(h, method, safe).map_err(|e| e.to_string()));
            let _ = tx.send(result);
            ctx.request_repaint();
        });
        self.rebuild_job = Some(RebuildJob {
            progress,
            result: rx,
            started: Instant::now(),
        });
    }

    pub(super) fn poll_jobs(&mut self) {
        if let Some(job) = &self.rebuild_job {
            match job.result.try_recv() {
                Ok(Ok(model)) => {
                    let secs = job.started.elapsed().as_secs_f64();
                    self.rebuild_job = None;
                    self.install(model);
                    self.status = format!("rebuilt in {secs:.1} s");
                    if let Ok(mut s) = self.summary.lock() {
                        s.rebuilds += 1;
                    }
                }
                Ok(Err(e)) => {
                    self.rebuild_job = None;
                    self.status = format!("rebuild failed: {e}");
                }
                Err(TryRecvError::Disconnected) => {
                    self.rebuild_job = None;
                    self.status = "rebuild failed: the build thread stopped".into();
                }
                Err(TryRecvError::Empty) => {}
            }
        }
        if let Some(job) = &self.truth_job {
            match job.result.try_recv() {
                Ok(visible) => {
                    let false_culls: Vec<bool> = visible.iter().zip(&job.drawn).map(|(&v, &d)| v && !d).collect();
                    let truth = Truth {
                        camera: job.camera,
                        drawn_fingerprint: job.drawn_fingerprint,
                        visible: visible.iter().filter(|&&v| v).count(),
                        count: false_culls.iter().filter(|&&f| f).count(),
                        false_culls,
                    };
                    if let Ok(mut s) = self.summary.lock() {
                        s.truth = Some((truth.visible, truth.count));
                    }
                    self.truth = Some(truth);
                    self.truth_job = None;
                }
                Err(TryRecvError::Disconnected) => {
                    self.truth_job = None;
                    self.status = "ground truth failed".into();
                }
                Err(TryRecvError::Empty) => {}
            }
        }
    }

    pub(super) fn install(&mut self, model: Model) {
        let colour = if model.terrain.hierarchy.is_some() {
            ColourMode::Groups
        } else {
            ColourMode::Height
        };
        let scene = model
            .terrain
            .colours(colour, None, None)
            .and_then(|c| GpuScene::new(&self.gpu, &model.terrain, &c));
        match scene {
            Ok(scene) => {
                self.scene = scene;
                self.colour = colour;
                self.colours_key = Some((colour, 0, 0));
                self.level = model.terrain.max_level();
                self.truth = None;
                self.model = model;
                self.map_dirty = true;
            }
            Err(e) => self.status = format!("cannot show the new hierarchy: {e}"),
        }
    }

    /// Starts the startup actions in order; true once they are all done.
    pub(super) fn startup_step(&mut self, ctx: &egui::Context) -> bool {
        if self.startup.rebuild {
            let rebuild = Arc::clone(&self.rebuild);
            self.start_rebuild(ctx, rebuild);
            self.startup.rebuild = false;
        }
        if self.rebuild_job.is_some() {
            return false;
        }
        if self.startup.ground_truth && self.model.culler.is_some() {
            self.start_truth(ctx);
            self.startup.ground_truth = false;
        }
        self.truth_job.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A truth taken at a 360° view once stayed on screen after the field of view was narrowed (and so for the yaw
    /// and the method): it holds only for its own camera and drawn set.
    #[test]
    fn a_truth_holds_only_for_its_camera_and_drawn_set() {
        let camera = Camera::from_degrees([1.0, 2.0, 3.0], 0.0, 360.0).expect("camera");
        let truth = Truth {
            camera,
            drawn_fingerprint: 7,
            visible: 0,
            false_culls: Vec::new(),
            count: 0,
        };
        assert!(truth.holds_for(&camera, 7));
        assert!(!truth.holds_for(&camera, 8), "another method or culler parameter");
        for other in [
            Camera::from_degrees([1.0, 2.0, 3.0], 0.0, 90.0),
            Camera::from_degrees([1.0, 2.0, 3.0], 10.0, 360.0),
            Camera::from_degrees([1.0, 2.0, 4.0], 0.0, 360.0),
        ] {
            assert!(!truth.holds_for(&other.expect("camera"), 7));
        }
    }
}
