//! Parameters of crystal grouping (thesis 5.2.3 and 6.3.2, Table 3).
//!
//! Defaults follow the thesis' experiments: groups under 30 triangles are orphaned, at most 10 orphan passes, and a
//! merge stops when the parent's circumscribed circle would cover more than 25% of the terrain's area. The thesis cast
//! 100 seeds on about 20,000 triangles and 500 on about 200,000; the default here is one seed per 200 triangles.

use serde::{Deserialize, Serialize};

use crate::error::CrystalError;

/// Parameters of [`crate::build`]. Read from TOML by the command-line tool; unknown keys are rejected.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CrystalParams {
    /// Seeds cast in the first pass; `None` means one per 200 triangles (at least 1).
    pub seeds: Option<usize>,
    /// Most orphan passes after the first pass.
    pub orphan_passes: u32,
    /// Smallest group kept; smaller groups are merged with a small group they collided with, or orphaned.
    pub min_group: usize,
    /// Largest parent node allowed in the hierarchy: its circumscribed circle's area as a fraction of the terrain's
    /// area (sum of triangle areas in x,y). `inf` disables the limit (written `"inf"` in JSON: see [`cull::limit`]).
    #[serde(with = "cull::limit")]
    pub max_expanse: f64,
    /// Seed of the random generator that places the seeds.
    pub rng_seed: u64,
}

impl Default for CrystalParams {
    fn default() -> Self {
        CrystalParams {
            seeds: None,
            orphan_passes: 10,
            min_group: 30,
            max_expanse: 0.25,
            rng_seed: 1,
        }
    }
}

impl CrystalParams {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), CrystalError> {
        let bad = |field: &'static str, reason: String| Err(CrystalError::InvalidParams { field, reason });
        if self.seeds == Some(0) {
            return bad(
                "seeds",
                "must be at least 1 (leave it out for one seed per 200 triangles)".into(),
            );
        }
        if self.min_group == 0 {
            return bad("min_group", "must be at least 1".into());
        }
        if self.max_expanse.is_nan() || self.max_expanse <= 0.0 {
            return bad(
                "max_expanse",
                format!(
                    "must be a positive fraction of the terrain's area, got {}",
                    tin::compact_number(self.max_expanse)
                ),
            );
        }
        Ok(())
    }

    /// The number of seeds of the first pass for a mesh of `triangles` triangles.
    pub fn first_seeds(&self, triangles: usize) -> usize {
        self.seeds.unwrap_or(triangles / 200).max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_follow_the_thesis() {
        let p = CrystalParams::default();
        p.validate().expect("defaults are valid");
        assert_eq!((p.orphan_passes, p.min_group, p.max_expanse), (10, 30, 0.25));
        assert_eq!(p.first_seeds(199), 1);
        assert_eq!(p.first_seeds(200_000), 1000);
        assert_eq!(CrystalParams { seeds: Some(7), ..p }.first_seeds(200_000), 7);
    }

    #[test]
    fn validation_names_the_field() {
        for (p, field) in [
            (
                CrystalParams {
                    seeds: Some(0),
                    ..Default::default()
                },
                "seeds",
            ),
            (
                CrystalParams {
                    min_group: 0,
                    ..Default::default()
                },
                "min_group",
            ),
            (
                CrystalParams {
                    max_expanse: f64::NAN,
                    ..Default::default()
                },
                "max_expanse",
            ),
            (
                CrystalParams {
                    max_expanse: -0.5,
                    ..Default::default()
                },
                "max_expanse",
            ),
        ] {
            match p.validate() {
                Err(CrystalError::InvalidParams { field: f, .. }) => assert_eq!(f, field),
                other => panic!("{field}: expected an error, got {other:?}"),
            }
        }
    }

    #[test]
    fn reads_toml_with_defaults_and_rejects_unknown_keys() {
        let p: CrystalParams = toml::from_str("seeds = 500\nmin_group = 40\n").expect("valid TOML");
        assert_eq!(p.seeds, Some(500));
        assert_eq!(p.min_group, 40);
        assert_eq!(p.orphan_passes, 10);
        assert_eq!(p.max_expanse, 0.25);
        let err = toml::from_str::<CrystalParams>("sedes = 5\n").expect_err("unknown key");
        assert!(err.to_string().contains("sedes"), "{err}");
        let round: CrystalParams = toml::from_str(&toml::to_string(&p).expect("serialises")).expect("reads back");
        assert_eq!(round, p);
    }
}
