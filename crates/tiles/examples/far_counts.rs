//! How many far-field points one tile takes as the terrain grows: a tile of 1,024 sample intervals in the middle of
//! square grids of 3,162², 10,000² and 40,000² samples (10M, 100M and a 1 m lidar county's 1.6 billion), level-0
//! blocks of 16 samples, halo 16, at `--far-ratio` 0 (every level-0 block), 8 and 16.
//!
//! ```sh
//! cargo run --release -p tiles --example far_counts
//! ```
//!
//! Only the geometry matters (every block has a point), so the far field is that of a flat grid, made without one
//! ([`FarField::flat`]).

use tiles::far_field::FarField;

fn main() {
    if std::env::args().len() > 1 {
        eprintln!("usage: far_counts (it takes no arguments)");
        std::process::exit(2);
    }
    let (block, halo, side) = (16usize, 16usize, 1024usize);
    println!("grid_side,samples,level0_blocks,ratio,far_points");
    for n in [3_162usize, 10_000, 40_000] {
        let far = FarField::flat([n, n], block);
        let k = n.div_ceil(block);
        let t0 = n / 2 - side / 2;
        let tile = [t0, t0 + side, t0, t0 + side];
        let window = [t0 - halo, t0 + side + halo, t0 - halo, t0 + side + halo];
        for ratio in [0, 8, 16] {
            let points = far.select(tile, window, ratio).len();
            println!("{n},{},{},{ratio},{points}", n * n, k * k);
        }
    }
}
