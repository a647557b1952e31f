//! The task's side of an episode's terrain (dm_control's split: the layout draws the physics, the
//! task judges it): what the progress term measures its way around and where an episode ends, as
//! generic [`Footprint`]s and bounds. [`Course::of`] is the one place where the env's settings say
//! which shapes of a [`Layout`] count for what; reward and termination read only the result.

use super::route::{route_distance_around, Capsule, Disc, Footprint};
use super::terrain::{Layout, TerrainDistribution};
use super::RewardConfig;
use crate::world_file::Ground;

/// What reward and termination need of the episode's terrain, in terms of no terrain type.
#[derive(Debug, Clone, Default)]
pub(super) struct Course {
    /// The footprints the progress term measures its way around (empty: the straight line).
    pub(super) route_around: Vec<Footprint>,
    /// Regions that end the episode (terminated, unsuccessful) once the base is inside one.
    pub(super) hazards: Vec<Footprint>,
    /// Half the extent along x and y of the ground: the episode ends (terminated, unsuccessful) once
    /// the base is beyond it, falling off the world (`None`: a ground without an edge).
    pub(super) edge: Option<(f64, f64)>,
}

impl Course {
    /// An episode's course over `layout`, drawn from `terrain`, under the reward settings `reward`:
    ///
    /// - with rough ground, its edge ends the episode;
    /// - with `terrain.rough.craters.terminate`, each crater's floor (the disc within `radius -
    ///   wall` of its centre) is a hazard;
    /// - with `reward.progress_around_craters`, the progress term goes around each crater widened
    ///   by `craters.clearance`, and with `reward.progress_around_ridges` around each ridge's
    ///   footprint (its crest line widened by half the crest, a side and `ridges.clearance`); with
    ///   both, the craters come first (see [`Course::progress_distance`]).
    pub(super) fn of(
        terrain: &TerrainDistribution,
        reward: &RewardConfig,
        layout: &Layout,
    ) -> Self {
        let mut course = Course::default();
        let Some(rough) = &terrain.rough else {
            return course;
        };
        if let Ground::Heightfield(h) = &layout.world.ground {
            course.edge = Some(h.half_extents());
        }
        let craters = &rough.craters;
        let widened = |by: f64| {
            layout.craters.iter().map(move |d| {
                Footprint::Disc(Disc {
                    radius: d.radius + by,
                    ..*d
                })
            })
        };
        if craters.terminate {
            course.hazards.extend(widened(-craters.wall));
        }
        if reward.progress_around_craters {
            course.route_around.extend(widened(craters.clearance));
        }
        if reward.progress_around_ridges {
            let ridges = &rough.ridges;
            let radius = ridges.half_width() + ridges.clearance;
            course.route_around.extend(
                layout
                    .ridges
                    .iter()
                    .map(|&segment| Footprint::Capsule(Capsule { segment, radius })),
            );
        }
        course
    }

    /// The distance the progress term measures with the base at `p` and the goal at `goal`:
    /// `straight` (the goal distance there) when there is nothing to go around, else
    /// [`route_distance_around`] the footprints.
    pub(super) fn progress_distance(&self, p: (f64, f64), goal: (f64, f64), straight: f64) -> f64 {
        if self.route_around.is_empty() {
            straight
        } else {
            route_distance_around(p, goal, &self.route_around)
        }
    }

    /// The episode ends (unsuccessfully) with the base at `p`: beyond the ground's edge or in a
    /// hazard.
    pub(super) fn ends_at(&self, p: (f64, f64)) -> bool {
        let off_ground = self
            .edge
            .is_some_and(|(hx, hy)| p.0.abs() > hx || p.1.abs() > hy);
        off_ground || self.hazards.iter().any(|f| f.contains(p.0, p.1))
    }
}
