//! Cameras: [`Camera::from_degrees`] refuses what makes no sense, and a camera built field by field with a wrong value
//! (a non-finite eye, a field of view that is not in `(0, 2π)`, such as degrees given for radians) never makes any
//! culler hide more than it would looking all around; and a draw list's mask never indexes past its end.

mod common;

use std::f64::consts::{FRAC_PI_4, TAU};

use cull::{AnyCuller, Camera, CameraError, CullMethod, DrawList};
use glam::DVec3;

use common::{grid_tin, hierarchy_of, notch};

#[test]
fn from_degrees_takes_what_the_command_line_and_the_c_api_take() {
    let eye = [1.0, 2.0, 3.0];
    let c = Camera::from_degrees(eye, 45.0, 90.0).expect("a valid view");
    assert_eq!((c.position, c.yaw, c.hfov), (eye, FRAC_PI_4, 2.0 * FRAC_PI_4));
    assert_eq!(c.frustum(), Some((FRAC_PI_4, FRAC_PI_4)));
    let all = Camera::from_degrees(eye, 10.0, 360.0).expect("all around");
    assert_eq!(all.hfov, TAU);
    assert_eq!(all.frustum(), None);
    assert_eq!(Camera::all_around(eye).frustum(), None);
    for fov in [0.0, -1.0, 360.5, f64::NAN, f64::INFINITY] {
        let e = Camera::from_degrees(eye, 0.0, fov).expect_err("no such field of view");
        assert!(matches!(e, CameraError::FieldOfView(_)), "{fov}: {e:?}");
        assert!(e.to_string().contains("(0, 360]"), "{e}");
    }
    assert!(matches!(
        Camera::from_degrees(eye, f64::NAN, 90.0),
        Err(CameraError::Yaw(_))
    ));
    let e = Camera::from_degrees([f64::INFINITY, 0.0, 0.0], 0.0, 90.0).expect_err("nowhere");
    assert!(
        matches!(e, CameraError::Eye(_)) && e.to_string().contains("not finite"),
        "{e}"
    );
}

#[test]
fn a_wrong_field_of_view_restricts_nothing() {
    let tin = grid_tin(21, 200.0, DVec3::ZERO, notch);
    let (h, _) = hierarchy_of(&tin, 16, 8);
    let eye = [40.0, 100.0, 2.0];
    for method in [CullMethod::Safe, CullMethod::Thesis, CullMethod::LloydEgbert] {
        let culler = AnyCuller::new(&h, method);
        let around = culler.cull(&Camera::all_around(eye));
        let narrow = culler.cull(&Camera::from_degrees(eye, 0.0, 30.0).expect("valid"));
        assert!(
            narrow.stats.culled_by_frustum > 0,
            "{method:?}: the test view must have something outside it"
        );
        for hfov in [0.0, -1.0, f64::NAN, 90.0, TAU, 1e9] {
            let list = culler.cull(&Camera {
                position: eye,
                yaw: 0.0,
                hfov,
            });
            assert_eq!(list.stats.culled_by_frustum, 0, "{method:?}, hfov {hfov}");
            assert_eq!(list.ranges, around.ranges, "{method:?}, hfov {hfov}");
        }
        // A finite field of view with a non-finite yaw has no direction: nothing is outside it.
        let list = culler.cull(&Camera {
            position: eye,
            yaw: f64::NAN,
            hfov: 1.0,
        });
        assert_eq!(list.ranges, around.ranges, "{method:?}, yaw NaN");
    }
}

#[test]
fn every_culler_draws_everything_from_a_camera_that_is_nowhere() {
    let tin = grid_tin(21, 200.0, DVec3::ZERO, notch);
    let (h, _) = hierarchy_of(&tin, 16, 8);
    let all = [0, h.num_triangles() as u32];
    for method in [CullMethod::Safe, CullMethod::Thesis, CullMethod::LloydEgbert] {
        let culler = AnyCuller::new(&h, method);
        for eye in [
            [f64::NAN, 0.0, 0.0],
            [f64::INFINITY, 100.0, 5.0],
            [100.0, 100.0, f64::NEG_INFINITY],
        ] {
            let mut list = DrawList::default();
            culler.cull_into(&Camera::all_around(eye), &mut list);
            assert_eq!(list.ranges, vec![all], "{method:?} from {eye:?}");
            assert_eq!(list.stats.culled_by_occlusion, 0);
        }
    }
}

#[test]
fn a_mask_shorter_than_the_draw_list_keeps_what_fits() {
    let mut list = DrawList::default();
    list.ranges = vec![[2, 4], [6, 9]];
    assert_eq!(
        list.mask(10),
        [false, false, true, true, false, false, true, true, true, false]
    );
    assert_eq!(list.mask(7), [false, false, true, true, false, false, true]);
    assert_eq!(list.mask(3), [false, false, true]);
    assert!(list.mask(0).is_empty());
}

/// Yaws a multiple of 360° apart are the same view, however large: `1e17` and `3.6e17` are exactly 280° and 0° in f64
/// (they once gave other frusta, reduced in radians).
#[test]
fn yaws_a_turn_apart_are_the_same_view() {
    let tin = grid_tin(21, 200.0, DVec3::ZERO, notch);
    let (h, _) = hierarchy_of(&tin, 16, 8);
    let eye = [40.0, 100.0, 2.0];
    for method in [CullMethod::Safe, CullMethod::Thesis, CullMethod::LloydEgbert] {
        let culler = AnyCuller::new(&h, method);
        for (yaw, same) in [
            (1e17, 280.0),
            (3.6e17, 0.0),
            (-1e17, -280.0),
            (720.0 + 45.0, 45.0),
            (-315.0, 45.0),
        ] {
            let a = culler.cull(&Camera::from_degrees(eye, yaw, 30.0).expect("valid"));
            let b = culler.cull(&Camera::from_degrees(eye, same, 30.0).expect("valid"));
            assert!(
                b.stats.culled_by_frustum > 0,
                "{method:?}: the view must leave something out"
            );
            assert_eq!(a.ranges, b.ranges, "{method:?}: yaw {yaw} against {same}");
        }
        // The narrowest field of view restricts the most, even below the smallest angle in radians (it once
        // restricted nothing).
        let narrow = culler.cull(&Camera::from_degrees(eye, 0.0, 1e-3).expect("valid"));
        for fov in [1e-322, 5e-324] {
            let tiny = culler.cull(&Camera::from_degrees(eye, 0.0, fov).expect("valid"));
            assert!(tiny.stats.culled_by_frustum > 0, "{method:?}: fov {fov}");
            assert!(
                tiny.stats.triangles_drawn <= narrow.stats.triangles_drawn,
                "{method:?}: fov {fov}"
            );
        }
    }
}

/// A camera built field by field with a yaw of many turns (radians) once hid what lies straight ahead, for every
/// culler: the view test subtracted the node's direction from the yaw itself, and at `|yaw| ≈ 1e17` that difference
/// keeps no digit (found by an audit). [`Camera::frustum`] now reduces such a yaw through its sine and cosine.
#[test]
fn a_yaw_of_many_turns_built_field_by_field_still_shows_what_lies_ahead() {
    let tin = grid_tin(21, 200.0, DVec3::ZERO, |_, _| 0.0);
    let (h, order) = hierarchy_of(&tin, 8, 0);
    let locator = truth::Locator::new(&tin);
    let eye = DVec3::new(100.0, 100.0, 2.0);
    for yaw in [1e3, 1e6, 1e9, 1e12, 1e15, 1e17, -1e17, 1e300, -f64::MAX] {
        let camera = Camera {
            position: eye.to_array(),
            yaw,
            hfov: 1.0,
        };
        let (yaw_reduced, half) = camera.frustum().expect("a finite yaw and a field of view in (0, 2π)");
        assert!(
            yaw_reduced.abs() <= std::f64::consts::PI && half == 0.5,
            "{yaw}: {yaw_reduced}"
        );
        // 50 m straight ahead on flat ground, in plain view.
        let ahead = eye + DVec3::new(50.0 * yaw.cos(), 50.0 * yaw.sin(), -2.0);
        let t = locator.locate(&tin, ahead.truncate()).expect("on the grid");
        let i = order
            .iter()
            .position(|&o| o as usize == t)
            .expect("every triangle ordered");
        for method in [CullMethod::Safe, CullMethod::Thesis, CullMethod::LloydEgbert] {
            let list = AnyCuller::new(&h, method).cull(&camera);
            assert!(
                list.mask(order.len())[i],
                "{method:?}, yaw {yaw:e}: triangle {t} straight ahead culled"
            );
            assert!(
                list.stats.culled_by_frustum > 0,
                "{method:?}, yaw {yaw:e}: the view must leave something out"
            );
        }
    }
}
