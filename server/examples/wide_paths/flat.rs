//! Surfaces over lanes, Mitsuba's way (`--simd-surface`).

use super::{R, V};
use pathstream::render::lanes::{Real, Vector};
use pathstream::render::math::Vec3A;
use pathstream::render::world::World;

/// Every placed triangle in camera space, for surfaces over lanes
/// (Mitsuba's way: the hit point from the ray, normals interpolated,
/// origins moved off by an epsilon): vertices' shading normals, each
/// triangle's face normal, whether it is smooth, its albedo and emission.
pub struct Flat {
    /// Each object's first flat triangle.
    pub first: Vec<u32>,
    pub tris: Vec<[u32; 3]>,
    pub vn: Vec<Vec3A>,
    pub ng: Vec<Vec3A>,
    pub smooth: Vec<bool>,
    pub albedo: Vec<Vec3A>,
    pub emission: Vec<Vec3A>,
}

/// Mitsuba's spawn over lanes: `p` moved (1 + max |p|) 1500 eps/2 off the
/// surface (normal `ng`) to the side `dir` leaves by.
#[inline(always)]
pub fn leave_lanes(p: V, ng: V, dir: V) -> V {
    let c = R::splat;
    let side = ng * c(1.0).copysign(dir.dot(ng));
    let m = p.x.abs().max(p.y.abs()).max(p.z.abs());
    p + side * ((c(1.0) + m) * c(1500.0 * f32::EPSILON / 2.0))
}

impl Flat {
    /// `world`'s placed triangles as `triangles` (flat vertex numbers) and
    /// `map` (each one's object and the object's first flat triangle) list
    /// them.
    pub fn build(world: &World, triangles: &[[u32; 3]], map: &[(u32, u32)]) -> Flat {
        let mut first = vec![0; world.objects.len()];
        for &(object, start) in map {
            first[object as usize] = start;
        }
        let mut f = Flat {
            first,
            tris: triangles.to_vec(),
            vn: Vec::new(),
            ng: Vec::new(),
            smooth: Vec::new(),
            albedo: Vec::new(),
            emission: Vec::new(),
        };
        for inst in &world.instances {
            let mesh = &inst.mesh;
            for i in 0..mesh.positions.len() {
                let n = mesh.normals.as_ref().map_or(Vec3A::ZERO, |n| {
                    (inst.normal_from_obj * Vec3A::from(n[i])).normalize_or_zero()
                });
                f.vn.push(n);
            }
            for prim in 0..mesh.triangles.len() as u32 {
                f.ng.push((inst.normal_from_obj * mesh.face_normal(prim)).normalize_or_zero());
                f.smooth
                    .push(mesh.shading_normal(prim, [1.0 / 3.0; 3]).is_some());
                let m = world.material(inst.materials[mesh.materials[prim as usize] as usize]);
                f.albedo.push(m.albedo);
                f.emission
                    .push(if m.emissive { m.emission } else { Vec3A::ZERO });
            }
        }
        f
    }
}
