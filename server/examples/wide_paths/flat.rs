//! Surfaces over lanes, Mitsuba's way (`--simd-surface`).

use super::{set, L, R, V};
use pathstream::render::lanes::U32s;
use pathstream::render::lanes::{Real, Vector};
use pathstream::render::math::{gamma, Vec3A};
use pathstream::render::world::World;

/// Every placed triangle in camera space, for surfaces over lanes
/// (Mitsuba's way: the hit point from the ray, normals interpolated,
/// origins moved off by an epsilon): vertices' shading normals, each
/// triangle's face normal, whether it is smooth, its albedo and emission.
pub struct Flat {
    /// Each object's first flat triangle.
    pub first: Vec<u32>,
    /// Each flat triangle's instance and its number in the instance's mesh.
    pub inst: Vec<(u32, u32)>,
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
            inst: Vec::new(),
            tris: triangles.to_vec(),
            vn: Vec::new(),
            ng: Vec::new(),
            smooth: Vec::new(),
            albedo: Vec::new(),
            emission: Vec::new(),
        };
        for (index, inst) in world.instances.iter().enumerate() {
            let mesh = &inst.mesh;
            f.inst
                .extend((0..mesh.triangles.len() as u32).map(|prim| (index as u32, prim)));
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

/// The renderer's robust spawn over lanes (`--robust-spawn`): each hit's
/// object-space point and its error bound (`triangle::hit_point`, the
/// instance's round trip), the origin moved that far along the object
/// normal and each coordinate rounded away from the plane, then mapped to
/// camera space (`Instance::spawn_origin`), every step over sixteen lanes.
pub struct Robust {
    p_obj: V,
    n_obj: V,
    dist: R,
    /// `cam_from_obj`: columns x, y, z and the translation.
    m: [V; 4],
}

/// The hit point's rounding bound (`triangle::hit_point`'s).
const GAMMA7: f32 = gamma(7);

impl Robust {
    /// The lanes' hits (flat triangle `prim[k]` at barycentrics `b`).
    #[inline(always)]
    pub fn gather(world: &World, flat: &Flat, prim: &[Option<u32>; L], b: &[R; 3]) -> Robust {
        let zero = V::splat_vec(Vec3A::ZERO);
        let (mut p, mut n_obj) = ([zero; 3], V::splat_vec(Vec3A::Z));
        let mut m = [zero; 4];
        let (mut ra, mut rb) = (R::splat(0.0), R::splat(0.0));
        for k in 0..L {
            let Some(i) = prim[k] else { continue };
            let (inst, local) = flat.inst[i as usize];
            let inst = &world.instances[inst as usize];
            let t = inst.mesh.triangles[local as usize];
            for j in 0..3 {
                set(
                    &mut p[j],
                    k,
                    Vec3A::from(inst.mesh.positions[t[j] as usize]),
                );
            }
            set(&mut n_obj, k, inst.mesh.face_normal(local));
            let a = &inst.cam_from_obj;
            set(&mut m[0], k, a.matrix3.x_axis);
            set(&mut m[1], k, a.matrix3.y_axis);
            set(&mut m[2], k, a.matrix3.z_axis);
            set(&mut m[3], k, a.translation);
            ra.0[k] = inst.rt_a;
            rb.0[k] = inst.rt_b;
        }
        let (t0, t1, t2) = (p[0] * b[0], p[1] * b[1], p[2] * b[2]);
        let p_obj = t0 + t1 + t2;
        let abs = |v: V| V::new(v.x.abs(), v.y.abs(), v.z.abs());
        let e = (abs(t0) + abs(t1) + abs(t2)) * R::splat(GAMMA7);
        let big = p_obj.x.abs().max(p_obj.y.abs()).max(p_obj.z.abs());
        let e = e + V::new(ra * big + rb, ra * big + rb, ra * big + rb);
        let dist = abs(n_obj).dot(e);
        Robust {
            p_obj,
            n_obj,
            dist,
            m,
        }
    }

    /// `q` (object space) in camera space.
    #[inline(always)]
    fn to_cam(&self, q: V) -> V {
        self.m[0] * q.x + self.m[1] * q.y + self.m[2] * q.z + self.m[3]
    }

    /// The hit points in camera space.
    #[inline(always)]
    pub fn point(&self) -> V {
        self.to_cam(self.p_obj)
    }

    /// The origins of rays leaving along `dir` (camera space; `ng` the
    /// camera-space normal that says the side).
    #[inline(always)]
    pub fn origin(&self, ng: V, dir: V) -> V {
        let d = self.dist * R::splat(1.0).copysign(dir.dot(ng));
        let shift = self.n_obj * d;
        let p = self.p_obj + shift;
        self.to_cam(V::new(
            away(p.x, shift.x),
            away(p.y, shift.y),
            away(p.z, shift.z),
        ))
    }
}

/// `x` moved one float in the direction of `shift`'s sign (none where it
/// is zero): `f32::next_up` and `next_down` over lanes, without branches.
#[inline(always)]
fn away(x: R, shift: R) -> R {
    let (b, s) = (x.to_bits(), shift.to_bits());
    let out: [u32; L] = std::array::from_fn(|k| {
        let (b, s) = (b.0[k], s.0[k]);
        // Same signs: away from zero (+1 on the bits), else toward it.
        let delta = 1u32.wrapping_sub(((b ^ s) >> 31) << 1);
        let moved = if b & 0x7fff_ffff == 0 {
            (s & 0x8000_0000) | 1
        } else {
            b.wrapping_add(delta)
        };
        if s & 0x7fff_ffff == 0 {
            b
        } else {
            moved
        }
    });
    R::from_bits(U32s(out))
}

/// The robust spawn in camera space, for a flat scene whose camera-space
/// vertices are the ones the tracer meets (`--robust-spawn=camera`): the
/// hit point from the barycentrics and its error bound, moved that far
/// along the camera-space face normal and rounded away. No instance
/// transform, so no round trip to bound.
pub struct RobustCam {
    p: V,
    n: V,
    dist: R,
}

impl RobustCam {
    #[inline(always)]
    pub fn gather(
        flat: &Flat,
        positions: &[[f32; 3]],
        prim: &[Option<u32>; L],
        b: &[R; 3],
    ) -> RobustCam {
        let zero = V::splat_vec(Vec3A::ZERO);
        let (mut p, mut n) = ([zero; 3], V::splat_vec(Vec3A::Z));
        for k in 0..L {
            let Some(i) = prim[k] else { continue };
            let t = flat.tris[i as usize];
            for j in 0..3 {
                set(&mut p[j], k, Vec3A::from(positions[t[j] as usize]));
            }
            set(&mut n, k, flat.ng[i as usize]);
        }
        let (t0, t1, t2) = (p[0] * b[0], p[1] * b[1], p[2] * b[2]);
        let abs = |v: V| V::new(v.x.abs(), v.y.abs(), v.z.abs());
        let e = (abs(t0) + abs(t1) + abs(t2)) * R::splat(GAMMA7);
        RobustCam {
            p: t0 + t1 + t2,
            n,
            dist: abs(n).dot(e),
        }
    }

    #[inline(always)]
    pub fn point(&self) -> V {
        self.p
    }

    #[inline(always)]
    pub fn origin(&self, dir: V) -> V {
        let shift = self.n * (self.dist * R::splat(1.0).copysign(dir.dot(self.n)));
        let q = self.p + shift;
        V::new(away(q.x, shift.x), away(q.y, shift.y), away(q.z, shift.z))
    }
}
