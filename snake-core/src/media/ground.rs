//! The ground giving way: a world whose plane ground holds granular media is built without the plane.
//! Instead, static boxes tile the plane's top (z = 0) everywhere outside the media's areas, and under
//! each area a floor box stands with its top at the medium's bottom, so a body sinks into the medium
//! until the medium holds it (or the floor stops it) and, outside it, rests on the ground as before.
//!
//! The tiling: the areas' x and y edges cut the square `[-GROUND_EXTENT, GROUND_EXTENT]^2` into a grid
//! of cells; a cell outside every area becomes a slab 1 m thick under z = 0 (the cells of one grid row
//! are merged into one box where they are consecutive), a cell inside an area a floor under its
//! bottom (the lowest bottom where areas overlap). The plane was infinite; the slabs end
//! `GROUND_EXTENT` metres from the origin, beyond any start and far beyond any episode's reach.

use crate::error::Result;
use crate::media::Medium;
use crate::world::{BodyId, StaticShape, World};

/// Half the side of the square the slabs cover, metres.
pub const GROUND_EXTENT: f64 = 1000.0;

/// Thickness of the slabs and floors, metres.
const SLAB: f64 = 1.0;

/// Builds the slabs and floors for the granular media among `media`; returns their bodies, the first
/// standing for the ground (friction and contacts name it).
pub fn build(media: &[Medium], world: &mut World) -> Result<Vec<BodyId>> {
    let regions: Vec<_> = media
        .iter()
        .filter_map(|m| match m {
            Medium::Granular(g) => Some(g.region),
            Medium::Water(_) => None,
        })
        .collect();
    let cut = |axis: usize| {
        let mut xs = vec![-GROUND_EXTENT, GROUND_EXTENT];
        for r in &regions {
            xs.push(r.min[axis].clamp(-GROUND_EXTENT, GROUND_EXTENT));
            xs.push(r.max[axis].clamp(-GROUND_EXTENT, GROUND_EXTENT));
        }
        xs.sort_by(f64::total_cmp);
        xs.dedup();
        xs
    };
    let (xs, ys) = (cut(0), cut(1));
    let mut bodies = Vec::new();
    let mut add = |world: &mut World, x0: f64, x1: f64, y0: f64, y1: f64, top: f64| -> Result<()> {
        let half = [0.5 * (x1 - x0), 0.5 * (y1 - y0), 0.5 * SLAB];
        let centre = [0.5 * (x0 + x1), 0.5 * (y0 + y1), top - 0.5 * SLAB];
        bodies.push(world.add_static(
            &StaticShape::Box { half_extents: half },
            centre,
            [0.0, 0.0, 0.0, 1.0],
        )?);
        Ok(())
    };
    for j in 0..ys.len() - 1 {
        let (y0, y1) = (ys[j], ys[j + 1]);
        let ym = 0.5 * (y0 + y1);
        // A run of consecutive cells of this row outside every area, merged into one slab.
        let mut run: Option<f64> = None;
        for i in 0..xs.len() - 1 {
            let (x0, x1) = (xs[i], xs[i + 1]);
            let xm = 0.5 * (x0 + x1);
            let bottom = regions
                .iter()
                .filter(|r| r.covers(xm, ym))
                .map(|r| r.min[2])
                .min_by(f64::total_cmp);
            match bottom {
                None => {
                    run.get_or_insert(x0);
                }
                Some(b) => {
                    if let Some(start) = run.take() {
                        add(world, start, x0, y0, y1, 0.0)?;
                    }
                    add(world, x0, x1, y0, y1, b)?;
                }
            }
        }
        if let Some(start) = run {
            add(world, start, *xs.last().expect("two edges"), y0, y1, 0.0)?;
        }
    }
    Ok(bodies)
}
