//! The world's meshes as one Embree scene, built from the scene's
//! placements alone, so that a camera move reuses it (`world::reuse`).
//!
//! A ray walks one tree where it can: meshes placed once (the smallest
//! first, up to [`FLAT_MAX_TRIANGLES`]) are triangles of the scene itself,
//! their vertices placed in f64 and rounded once; a mesh placed more than
//! once, or beyond that budget, is an instance of its own mesh scene
//! (built once per mesh, kept with it). Instances cost Embree a second
//! walk and the ray's map into object space: one instance holding all of
//! `cornell-mesh` traced 5% slower in lanes, 19% slower one ray at a time
//! (docs/BENCHMARKS.md, "One tree for Embree").
//!
//! The scene sits in a frame of its own, the centre of the meshes' world
//! boxes (f32 keeps the scene's precision wherever it sits). Rays, which
//! are in camera space, are moved into it by a translation before each
//! query ([`Frame::shift`]), which leaves distances and barycentrics as
//! they are: the rounding of that move is the one an instance placed by a
//! translation makes.

use super::reuse::Reuse;
use super::{Geometry, World};
use crate::render::embree::{Embree, Part, WorldScene};
use crate::render::math::{DAffine3, DVec3, Vec3A};
use crate::render::shape::Mesh;
use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// Most triangles of meshes placed once that the scene holds as its own.
/// An edit that moves one of them (not a camera move) builds the scene
/// again: at Embree's rate here (246,000 triangles in 53 ms on two cores)
/// about 0.1 s at this bound, and each scene kept holds a copy of them.
pub const FLAT_MAX_TRIANGLES: usize = 1 << 19;

/// Scenes of the last worlds rendered.
static SCENES: Reuse<Arc<Frame>> = Reuse::new(4);

/// The scene and where it sits.
pub(super) struct Frame {
    pub scene: WorldScene,
    /// World-space position of the scene's origin.
    pub centre: DVec3,
    pub layout: EmbreeLayout,
}

/// How the world's Embree scene holds its meshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmbreeLayout {
    /// Triangles that are the scene's own.
    pub own_triangles: usize,
    /// Meshes placed as instances of their own scenes.
    pub instances: usize,
    /// Which build of the process this scene is (the first is 1): a
    /// world that reuses a scene reports the same number.
    pub build: u64,
}

/// Scenes built so far.
static BUILDS: AtomicU64 = AtomicU64::new(0);

impl Frame {
    /// What moves a camera-space point of `world` into the scene's frame.
    pub fn shift(&self, world: &World) -> Vec3A {
        (world.origin - self.centre).as_vec3a()
    }
}

/// A placement `at` (world from object) moved into the frame centred at
/// `centre`.
pub(super) fn placed_in(at: &DAffine3, centre: DVec3) -> DAffine3 {
    DAffine3 {
        matrix3: at.matrix3,
        translation: at.translation - centre,
    }
}

/// Object-space point `p` placed by `here` (from [`placed_in`]): in f64,
/// rounded once, as the scene holds its own triangles' vertices.
#[inline]
pub(super) fn frame_point(here: &DAffine3, p: [f32; 3]) -> [f32; 3] {
    here.transform_point3(DVec3::from(p.map(f64::from)))
        .as_vec3()
        .to_array()
}

/// The scene for `world`'s placed meshes, from the cache or built.
pub(super) fn frame(world: &World, embree: &'static Embree) -> Result<Arc<Frame>, String> {
    let placed: Vec<_> = (world.objects.iter().enumerate())
        .filter_map(|(id, o)| match o.geometry {
            Geometry::Instance(i) => {
                let instance = &world.instances[i as usize];
                Some((id as u32, &instance.mesh, &instance.world_from_obj))
            }
            _ => None,
        })
        .collect();
    SCENES.get_or_build(&placed, || build(&placed, embree).map(Arc::new))
}

fn build(
    placed: &[(u32, &Arc<Mesh>, &DAffine3)],
    embree: &'static Embree,
) -> Result<Frame, String> {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let mut placements = HashMap::<*const Mesh, usize>::new();
    for &(_, mesh, at) in placed {
        let (l, h) = mesh.bounds().transformed(at);
        (lo, hi) = (lo.min(l), hi.max(h));
        *placements.entry(Arc::as_ptr(mesh)).or_default() += 1;
    }
    let centre = match lo.is_finite() && hi.is_finite() {
        true => (lo + hi) * 0.5,
        false => DVec3::ZERO,
    };
    // Meshes placed once, the smallest first, while they fit the budget.
    let mut once: Vec<usize> = (0..placed.len())
        .filter(|&k| placements[&Arc::as_ptr(placed[k].1)] == 1)
        .collect();
    once.sort_by_key(|&k| (placed[k].1.triangles.len(), k));
    let mut flat = vec![false; placed.len()];
    let mut total = 0;
    for k in once {
        let n = placed[k].1.triangles.len();
        if total + n <= FLAT_MAX_TRIANGLES {
            (flat[k], total) = (true, total + n);
        }
    }
    let mut parts = Vec::with_capacity(placed.len());
    for (&(id, mesh, at), flat) in placed.iter().zip(flat) {
        let here = placed_in(at, centre);
        // Placed vertices beyond f32's range stay in object space.
        let positions = flat.then(|| {
            (mesh.positions.iter())
                .map(|&p| frame_point(&here, p))
                .collect::<Vec<_>>()
        });
        if let Some(positions) = positions.filter(|v| v.iter().flatten().all(|c| c.is_finite())) {
            let triangles = &mesh.triangles;
            parts.push(Part::Triangles {
                id,
                positions,
                triangles,
            });
        } else {
            let (m, t) = (here.matrix3.as_mat3(), here.translation.as_vec3());
            let matrix = [
                m.x_axis.x, m.x_axis.y, m.x_axis.z, m.y_axis.x, m.y_axis.y, m.y_axis.z, m.z_axis.x,
                m.z_axis.y, m.z_axis.z, t.x, t.y, t.z,
            ];
            let mesh = mesh.embree_scene(embree)?;
            parts.push(Part::Placed { id, mesh, matrix });
        }
    }
    let (mut own_triangles, mut instances) = (0, 0);
    for part in &parts {
        match part {
            Part::Triangles { triangles, .. } => own_triangles += triangles.len(),
            Part::Placed { .. } => instances += 1,
        }
    }
    let started = std::time::Instant::now();
    let scene = embree.scene(parts)?;
    tracing::debug!(
        placed = placed.len(),
        own_triangles,
        ms = started.elapsed().as_secs_f64() * 1e3,
        "built the world's Embree scene"
    );
    let layout = EmbreeLayout {
        own_triangles,
        instances,
        build: BUILDS.fetch_add(1, Ordering::Relaxed) + 1,
    };
    Ok(Frame {
        scene,
        centre,
        layout,
    })
}
