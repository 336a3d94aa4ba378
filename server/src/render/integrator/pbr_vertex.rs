//! A `pbr` surface's part of a path vertex, built once and shared by the
//! vertex's next-event estimation and its scatter: the shading frame, the
//! outgoing direction in it and the GGX lobes seen from there; and what the
//! surface makes of light from a direction, weighed against BSDF sampling
//! (`mis`). The scalar path (`Path::step`) and the wide loop's lanes
//! (`backend::cpu`) both evaluate it, one lane at a time: one description
//! of the BSDF's light for every CPU loop.

use super::mis::{self, Combine};
use crate::render::ggx::{self, Pbr};
use crate::render::math::{basis, Vec3A};

/// A `pbr` vertex: the material, and the lobes built for it.
#[derive(Clone, Copy, Debug)]
pub struct PbrVertex {
    p: Pbr,
    albedo: Vec3A,
    /// The shading frame (tangent, bitangent, the unit shading normal on
    /// the side the ray came from).
    t: Vec3A,
    b: Vec3A,
    ns: Vec3A,
    /// Towards where the ray came from, in the frame.
    wo: Vec3A,
    pub lobes: ggx::Lobes,
}

impl PbrVertex {
    /// The vertex of a ray along `d` that met material `p` (base colour
    /// `albedo`) from outside (`entering`, by the geometric normal) or
    /// inside, `ns` its shading normal on the ray's side, `nc` a clear
    /// coat's own unit normal where it has one (on the same side).
    #[inline(always)]
    pub fn new(
        p: &Pbr,
        albedo: Vec3A,
        d: Vec3A,
        (ns, entering): (Vec3A, bool),
        nc: Option<Vec3A>,
    ) -> Self {
        let (t, b) = basis(ns);
        let local = |v: Vec3A| Vec3A::new(v.dot(t), v.dot(b), v.dot(ns));
        let wo = -local(d);
        let frame = nc.map(|n| ggx::coat::Frame::new(local(n)));
        let lobes = ggx::Lobes::framed(ggx::tables(), p, albedo, (wo, entering), frame);
        PbrVertex {
            p: *p,
            albedo,
            t,
            b,
            ns,
            wo,
            lobes,
        }
    }

    /// What the surface makes of unit light arriving along `dir`, drawn
    /// by a light sample with density `light_pdf`: BSDF cos, weighed as
    /// `combine` says against the BSDF's own density of `dir`.
    #[inline(always)]
    pub fn light(&self, combine: Combine, dir: Vec3A, light_pdf: f32) -> Vec3A {
        let wi = Vec3A::new(dir.dot(self.t), dir.dot(self.b), dir.dot(self.ns));
        let bsdf_pdf = ggx::pdf(&self.p, &self.lobes, self.wo, wi);
        let w = mis::light_weight(combine, light_pdf, bsdf_pdf);
        ggx::eval_cos(
            ggx::tables(),
            &self.p,
            self.albedo,
            &self.lobes,
            self.wo,
            wi,
        ) * w
    }
}
