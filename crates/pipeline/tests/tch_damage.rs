//! A `.tch` file whose payload was damaged and whose header was then made to match it again (as a faulty writer or a
//! crafted file would: the checksum says nothing then) is read back as a hierarchy that passes every invariant check
//! and culls with every method that applies, from any eye, or refused with an error; never a panic.

use std::path::Path;

use cull::{AnyCuller, Camera, CullMethod, Hierarchy, SafeParams};
use proptest::prelude::*;

/// jacksboro-2k's default build and its `.tch` payload, made once for all the cases below.
fn original() -> &'static (Hierarchy, Vec<u8>) {
    static ORIGINAL: std::sync::OnceLock<(Hierarchy, Vec<u8>)> = std::sync::OnceLock::new();
    ORIGINAL.get_or_init(|| {
        let obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../meshes/jacksboro-2k.obj");
        let (t, _) = tin::read_obj(&obj, &tin::ObjImportOptions::default()).expect("the bundled mesh");
        let h = pipeline::build(&t, &pipeline::BuildParams::default(), None)
            .expect("build")
            .hierarchy;
        let bytes = h.to_bytes().expect("encodes");
        let payload = bytes[cull::file::HEADER_LEN..].to_vec();
        (h, payload)
    })
}

/// How a payload is damaged.
#[derive(Clone, Debug)]
enum Damage {
    /// The byte at this position (modulo the length) replaced.
    Set(usize, u8),
    /// A byte inserted before this position.
    Insert(usize, u8),
    /// The byte at this position removed.
    Remove(usize),
}

fn damage() -> impl Strategy<Value = Damage> {
    let byte = prop_oneof![any::<u8>(), Just(0u8), Just(0x7f), Just(0x80), Just(0xff)];
    prop_oneof![
        6 => (any::<usize>(), byte.clone()).prop_map(|(at, b)| Damage::Set(at, b)),
        1 => (any::<usize>(), byte).prop_map(|(at, b)| Damage::Insert(at, b)),
        1 => any::<usize>().prop_map(Damage::Remove),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn a_tch_with_its_payload_damaged_is_read_or_refused(
        damages in prop::collection::vec(damage(), 1..4),
        eye in (0.0f64..1.0, 0.0f64..1.0, prop_oneof![Just(2.0f64), Just(50.0), Just(2000.0), -10.0f64..500.0]),
    ) {
        let (h, payload) = original();
        let mut p = payload.clone();
        for d in &damages {
            match *d {
                Damage::Set(at, b) => {
                    let n = p.len();
                    p[at % n] = b;
                }
                Damage::Insert(at, b) => p.insert(at % (p.len() + 1), b),
                Damage::Remove(at) => {
                    let n = p.len();
                    p.remove(at % n);
                }
            }
        }
        let bytes = cull::file::frame(&cull::MAGIC, cull::FORMAT_VERSION, &p);
        if let Ok(back) = Hierarchy::from_bytes(&bytes) {
            back.check_invariants().expect("what is read back is a valid hierarchy");
            // Eyes over the original terrain's footprint (the damage may have moved it).
            let lo = h.mesh.positions.iter().fold([f64::MAX; 2], |m, q| [m[0].min(q[0]), m[1].min(q[1])]);
            let hi = h.mesh.positions.iter().fold([f64::MIN; 2], |m, q| [m[0].max(q[0]), m[1].max(q[1])]);
            let at = [lo[0] + eye.0 * (hi[0] - lo[0]), lo[1] + eye.1 * (hi[1] - lo[1]), eye.2];
            let params = [
                SafeParams::default(),
                SafeParams { coarse_columns: 8, ..SafeParams::default() },
                SafeParams { work_budget: 150, ..SafeParams::default() },
            ];
            for method in CullMethod::ALL {
                if method.check(&back).is_err() {
                    continue;
                }
                for safe in params {
                    let culler = AnyCuller::with_params(&back, method, safe);
                    for camera in [Camera::all_around(at), Camera { position: at, yaw: 1.0, hfov: 1.2 }] {
                        let drawn = culler.cull(&camera);
                        prop_assert!(drawn.ranges.iter().all(|r| r[0] < r[1] && r[1] as usize <= back.num_triangles()));
                    }
                }
            }
        }
    }
}
