//! A validated scene turned into the hot path's world, relative to a render
//! origin, with its accelerator chosen.
//!
//! Boxes of objects for the BVH are computed in f64 and padded: by a
//! relative 1e-4 of their size and position for spheres (whose f32 test is
//! accurate to the rounding of |o||c|/r, see `shape::sphere`), and 1e-5 for
//! quads and mesh instances (whose rays are mapped into object space with
//! f32 matrices). The padding costs nothing measurable and keeps the BVH
//! from culling a hit that the scan would report.

use super::emitters::Sky;
use super::merge::Placement;
use super::{Accel, Geometry, Instance, World, WorldObject};
use crate::render::alpha::AlphaMode;
use crate::render::bvh::{Aabb, Bvh};
use crate::render::light::{EnvLight, SunLight};
use crate::render::material::SurfaceMaterial;
use crate::render::math::{DAffine3, DVec3, Vec3A};
use crate::render::scene::{Scene, Shape};
use crate::render::shape::{Mesh, Quad, Sphere, SphereBatch, SPHERE_BATCH_LANES};
use std::sync::Arc;

/// Scenes whose scan costs at most this much (and without meshes) are
/// scanned, not searched through a BVH; see [`scan_cost`]. Measured with
/// `cargo run --release --example accel_crossover` (docs/BENCHMARKS.md):
/// the BVH catches up at about 256 spheres, or 9 spheres and 8 quads.
pub const SCAN_MAX_COST: usize = 32;

/// What scanning costs per ray, in units of one 8-sphere SIMD batch: a
/// quad's test costs about four batches.
pub fn scan_cost(spheres: usize, quads: usize) -> usize {
    spheres.div_ceil(8) + 4 * quads
}

/// Which accelerator a world uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AccelChoice {
    /// The scan for a few spheres and quads, else the BVH.
    #[default]
    Auto,
    /// Always the BVH (tests compare it with the brute-force search).
    Bvh,
    /// The scan whenever the scene has no meshes (to measure the crossover).
    Scan,
}

impl World {
    /// The scene relative to `origin` (normally the camera position).
    pub fn new(scene: &Scene, origin: DVec3) -> Self {
        Self::with_accel(scene, origin, AccelChoice::Auto)
    }

    /// The scene relative to `origin` with the accelerator `choice`.
    pub fn with_accel(scene: &Scene, origin: DVec3, choice: AccelChoice) -> Self {
        Self::build(scene, origin, choice, true)
    }

    /// As [`World::with_accel`], every mesh on its own instance (none
    /// merged, `world::merge`): what merging must agree with.
    pub fn unmerged(scene: &Scene, origin: DVec3, choice: AccelChoice) -> Self {
        Self::build(scene, origin, choice, false)
    }

    fn build(scene: &Scene, origin: DVec3, choice: AccelChoice, merge: bool) -> Self {
        let mut materials: Vec<SurfaceMaterial> =
            scene.materials.iter().map(SurfaceMaterial::new).collect();
        let (textures, maps) = super::textures::world_maps(scene, &mut materials);
        let mut objects = Vec::with_capacity(scene.objects.len());
        let mut instances = Vec::new();
        let mut boxes = Vec::with_capacity(scene.objects.len());
        // Every mesh placement, in object order; small ones merge (`merge`).
        let placements: Vec<Placement<'_>> = (scene.objects.iter())
            .filter_map(|o| match o.shape {
                Shape::Import(k) => Some(&scene.imports[k].instances),
                _ => None,
            })
            .flatten()
            .map(|inst| Placement {
                mesh: &inst.mesh,
                world_from_object: inst.world_from_object,
                materials: &inst.materials,
            })
            .collect();
        let merged = match merge {
            true => super::merge::merge(&placements),
            false => Vec::new(),
        };
        // Per placement: its merged group, if any.
        let mut group_of = vec![None; placements.len()];
        for (g, m) in merged.iter().enumerate() {
            for &i in &m.members {
                group_of[i] = Some(g);
            }
        }
        let mut placement = 0;
        for o in &scene.objects {
            match o.shape {
                Shape::Sphere { center, radius } => {
                    let c = center - origin;
                    objects.push(WorldObject {
                        geometry: Geometry::Sphere(Sphere::new(c, radius)),
                        material: o.material as u32,
                    });
                    let r = DVec3::splat(radius);
                    boxes.push(padded(c - r, c + r, 1e-4));
                }
                Shape::Quad {
                    corner,
                    edge_u,
                    edge_v,
                } if scene.materials[o.material].maps.alpha_mode != AlphaMode::Opaque => {
                    let world_from_object = super::cutout::square_placement(corner, edge_u, edge_v);
                    let materials: Arc<[u32]> = [o.material as u32].into();
                    let mesh = super::cutout::unit_square();
                    let placed = instance(scene, mesh, world_from_object, origin, materials);
                    push_instance(&mut objects, &mut instances, &mut boxes, placed);
                }
                Shape::Quad {
                    corner,
                    edge_u,
                    edge_v,
                } => {
                    let c = corner - origin;
                    objects.push(WorldObject {
                        geometry: Geometry::Quad(Quad::new(c, edge_u, edge_v)),
                        material: o.material as u32,
                    });
                    let corners = [c, c + edge_u, c + edge_v, c + edge_u + edge_v];
                    let (lo, hi) = corners
                        .iter()
                        .fold((corners[0], corners[0]), |(lo, hi), &p| {
                            (lo.min(p), hi.max(p))
                        });
                    boxes.push(padded(lo, hi, 1e-5));
                }
                Shape::Import(k) => {
                    for inst in &scene.imports[k].instances {
                        let this = placement;
                        placement += 1;
                        // A merged group is placed where its first member is.
                        let (mesh, world_from_object, materials) = match group_of[this] {
                            None => (
                                inst.mesh.clone(),
                                inst.world_from_object,
                                inst.materials.clone(),
                            ),
                            Some(g) if merged[g].members[0] == this => {
                                let m = &merged[g];
                                let frame = DAffine3::from_translation(m.frame);
                                (m.mesh.clone(), frame, m.materials.clone())
                            }
                            Some(_) => continue,
                        };
                        let placed = instance(scene, mesh, world_from_object, origin, materials);
                        push_instance(&mut objects, &mut instances, &mut boxes, placed);
                    }
                }
            }
        }
        let scene_box = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let radius = if scene_box.is_empty() {
            1.0
        } else {
            f64::from(scene_box.extent().length()) * 0.5
        };
        let environment: Vec3A = scene.environment.as_vec3().into();
        let env_map = scene.environment_map.as_ref().map(|m| {
            let j = &m.json;
            Arc::new(EnvLight::new(
                m.map.clone(),
                j.intensity,
                j.rotation_deg,
                j.visible,
                DVec3::from_array(j.background.unwrap_or([0.0; 3])),
            ))
        });
        let sky = match &env_map {
            Some(m) => Sky::Map(m.clone()),
            None => Sky::Uniform(environment),
        };
        // A computed sky's sun, turned with its map and scaled by its intensity.
        let sun = scene.environment_map.as_ref().zip(env_map.as_ref());
        let sun = sun.and_then(|(m, light)| {
            let disc = m.sun?;
            let dir = light.map_to_world(Vec3A::from(disc.dir.as_vec3()));
            let radiance =
                Vec3A::from(DVec3::from_array(disc.radiance).as_vec3()) * light.intensity;
            Some((SunLight::new(dir.normalize(), disc.radius), radiance))
        });
        let with_maps = super::emitters::Materials {
            list: &materials,
            maps: &maps,
            textures: &textures,
        };
        let lights = super::emitters::lights(&objects, &instances, &with_maps, (sun, sky), radius);
        let scan = instances.is_empty()
            && match choice {
                AccelChoice::Auto => {
                    let quads = objects
                        .iter()
                        .filter(|o| matches!(o.geometry, Geometry::Quad(_)))
                        .count();
                    scan_cost(objects.len() - quads, quads) <= SCAN_MAX_COST
                }
                AccelChoice::Bvh => false,
                AccelChoice::Scan => true,
            };
        let accel = if scan {
            let mut spheres = Vec::new();
            let mut quads = Vec::new();
            for (i, o) in objects.iter().enumerate() {
                match o.geometry {
                    Geometry::Sphere(s) => spheres.push((i as u32, s)),
                    Geometry::Quad(q) => quads.push((i as u32, q)),
                    Geometry::Instance(_) => unreachable!("scanned worlds have no instances"),
                }
            }
            Accel::Scan {
                sphere_batches: spheres
                    .chunks(SPHERE_BATCH_LANES)
                    .map(SphereBatch::new)
                    .collect(),
                quads,
                boxes,
                bvh: std::sync::OnceLock::new(),
            }
        } else {
            let (bvh, big) = object_bvh(&objects, &boxes);
            Accel::Bvh {
                bvh,
                big: sphere_batches(&objects, &big),
            }
        };
        let vertex_colors = instances.iter().any(|i| i.mesh.colors.is_some());
        let translated_meshes = instances.iter().any(|i| i.translation_only);
        let placed_triangles = instances.iter().map(|i| i.triangles()).sum();
        Self {
            origin,
            objects,
            instances,
            materials,
            textures,
            maps,
            vertex_colors,
            translated_meshes,
            placed_triangles,
            lights,
            environment,
            env_map,
            sun,
            accel,
            accel_choice: choice,
            embree: std::sync::OnceLock::new(),
        }
    }
}

/// `mesh` placed by `world_from_object` relative to `origin`, with its
/// alpha tests, and its padded box.
fn instance(
    scene: &Scene,
    mesh: Arc<Mesh>,
    world_from_object: DAffine3,
    origin: DVec3,
    materials: Arc<[u32]>,
) -> (Instance, Aabb) {
    let cam_from_obj = DAffine3 {
        matrix3: world_from_object.matrix3,
        translation: world_from_object.translation - origin,
    };
    let (lo, hi) = mesh.bounds().transformed(&cam_from_obj);
    let mut placed = Instance::new(mesh, world_from_object, origin, materials);
    placed.alpha = super::textures::alpha_tests(scene, &placed.materials);
    (placed, padded(lo, hi, 1e-5))
}

/// Adds `placed` (an instance and its box) as the next object.
fn push_instance(
    objects: &mut Vec<WorldObject>,
    instances: &mut Vec<Instance>,
    boxes: &mut Vec<Aabb>,
    (placed, bounds): (Instance, Aabb),
) {
    objects.push(WorldObject {
        geometry: Geometry::Instance(instances.len() as u32),
        material: u32::MAX,
    });
    instances.push(placed);
    boxes.push(bounds);
}

/// A BVH over the objects that are not too large for one, and those
/// (ascending), which are tested one by one before it.
pub(super) fn object_bvh(objects: &[WorldObject], boxes: &[Aabb]) -> (Bvh, Vec<u32>) {
    let big = big_spheres(objects, boxes);
    let is_big = |i: usize| big.binary_search(&(i as u32)).is_ok();
    let ids: Vec<u32> = (0..boxes.len())
        .filter(|&i| !is_big(i))
        .map(|i| i as u32)
        .collect();
    let mut bvh = Bvh::build(&ids.iter().map(|&i| boxes[i as usize]).collect::<Vec<_>>());
    for p in &mut bvh.prims {
        *p = ids[*p as usize];
    }
    (bvh, big)
}

/// The spheres among `ids`, eight to a batch.
fn sphere_batches(objects: &[WorldObject], ids: &[u32]) -> Vec<SphereBatch> {
    let spheres: Vec<(u32, Sphere)> = ids
        .iter()
        .filter_map(|&i| match objects[i as usize].geometry {
            Geometry::Sphere(s) => Some((i, s)),
            _ => None,
        })
        .collect();
    spheres
        .chunks(SPHERE_BATCH_LANES)
        .map(SphereBatch::new)
        .collect()
}

/// The spheres that enclose the scene: whose boxes hold at least three
/// quarters of the other objects' centres (walls made of huge spheres, a
/// furnace's shell). Nearly every ray enters their boxes, so the BVH could
/// not cull them; they are tested first, eight at a time. Only the 64
/// largest spheres are candidates.
fn big_spheres(objects: &[WorldObject], boxes: &[Aabb]) -> Vec<u32> {
    let mut spheres: Vec<(f32, u32)> = objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| match o.geometry {
            Geometry::Sphere(s) => Some((s.radius, i as u32)),
            _ => None,
        })
        .collect();
    spheres.sort_by(|a, b| b.0.total_cmp(&a.0));
    spheres.truncate(64);
    let centers: Vec<Vec3A> = boxes.iter().map(Aabb::centroid).collect();
    let others = centers.len().saturating_sub(1);
    let mut big: Vec<u32> = spheres
        .iter()
        .filter(|&&(_, i)| {
            let b = &boxes[i as usize];
            let held = centers
                .iter()
                .enumerate()
                .filter(|&(j, c)| j != i as usize && b.contains(*c))
                .count();
            4 * held >= 3 * others
        })
        .map(|&(_, i)| i)
        .collect();
    big.sort_unstable();
    big
}

/// The f32 box holding [lo, hi] grown by `rel` of its size and position.
fn padded(lo: DVec3, hi: DVec3, rel: f64) -> Aabb {
    let scale = (hi - lo)
        .max_element()
        .max(lo.abs().max_element())
        .max(hi.abs().max_element());
    let pad = DVec3::splat(rel * scale + f64::from(f32::MIN_POSITIVE));
    Aabb::new((lo - pad).as_vec3().into(), (hi + pad).as_vec3().into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::scene::builtin;

    fn big_of(name: &str) -> usize {
        let s = builtin(name).expect("built-in");
        let w = World::with_accel(&s, s.camera.position, AccelChoice::Bvh);
        match &w.accel {
            Accel::Bvh { big, bvh } => {
                let n: usize = big
                    .iter()
                    .map(|b| b.ids.iter().filter(|&&id| id >= 0.0).count())
                    .sum();
                assert_eq!(
                    n + bvh.prims.len(),
                    w.objects.len(),
                    "{name}: every object is in one place"
                );
                n
            }
            Accel::Scan { .. } => panic!("forced BVH"),
        }
    }

    #[test]
    fn spheres_that_dwarf_the_scene_are_scanned_not_put_in_the_bvh() {
        // smallpt: the six radius-1e5 walls, not the radius-600 light above.
        assert_eq!(big_of("smallpt"), 6);
        // cornell with a field of small spheres: still the walls only.
        // cornell: the six walls, not the radius-7 lamp.
        assert_eq!(big_of("cornell"), 6);
        assert_eq!(big_of("furnace"), 1);
        // cornell-quads: the walls are quads; the balls and lamp are small.
        assert_eq!(big_of("cornell-quads"), 0);
    }

    #[test]
    fn auto_scans_what_scanning_is_cheaper_for() {
        let scans = |name: &str| {
            let s = builtin(name).expect("built-in");
            matches!(World::new(&s, s.camera.position).accel, Accel::Scan { .. })
        };
        for name in [
            "cornell",
            "cornell-glass",
            "cornell-quads",
            "smallpt",
            "furnace",
        ] {
            assert!(scans(name), "{name} is scanned");
        }
        // The crossovers measured by the accel_crossover example.
        assert!(scan_cost(256, 0) <= SCAN_MAX_COST && scan_cost(264, 0) > SCAN_MAX_COST);
        assert!(scan_cost(9, 6) <= SCAN_MAX_COST && scan_cost(9, 8) > SCAN_MAX_COST);
    }
}
