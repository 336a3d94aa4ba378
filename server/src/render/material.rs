//! Surface scattering: diffuse (cosine-weighted), mirror, smooth glass, and
//! glTF's metallic-roughness model (`render::ggx`).

use crate::render::fresnel;
use crate::render::ggx::{self, Pbr};
use crate::render::lanes::{Real, Vector};
use crate::render::math::{basis, sincos_turns, DVec3, Vec3A};
use crate::render::sampler::Sampler;
use crate::render::scene::{Fresnel, Material, MaterialKind};

/// `SurfaceMaterial::maps` of a material without texture maps.
pub const NO_MAPS: u32 = u32::MAX;

/// How a material scatters, in the hot path's form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    Diffuse,
    Mirror,
    Glass { ior: f32, schlick: bool },
    Pbr(Pbr),
}

impl Bsdf {
    /// Whether next-event estimation gathers (some of) the light this
    /// surface reflects (else the path counts emission at its next hit).
    #[inline(always)]
    pub fn gathers_light(&self) -> bool {
        matches!(self, Bsdf::Diffuse | Bsdf::Pbr(_))
    }
}

#[derive(Clone, Copy, Debug)]
pub struct SurfaceMaterial {
    pub bsdf: Bsdf,
    pub albedo: Vec3A,
    pub emission: Vec3A,
    pub emissive: bool,
    /// Its texture maps in `World::maps`, or [`NO_MAPS`].
    pub maps: u32,
    /// The absorption coefficient inside (per scene unit; zero: clear):
    /// a ray that reaches this surface from inside has crossed the solid.
    pub absorb: Vec3A,
}

fn f32x3(v: DVec3) -> Vec3A {
    v.as_vec3().into()
}

impl SurfaceMaterial {
    pub fn new(m: &Material) -> Self {
        let bsdf = match m.kind {
            MaterialKind::Diffuse => Bsdf::Diffuse,
            MaterialKind::Mirror => Bsdf::Mirror,
            MaterialKind::Glass { ior, fresnel } => Bsdf::Glass {
                ior: ior as f32,
                schlick: fresnel == Fresnel::Schlick,
            },
            MaterialKind::Pbr {
                metallic,
                roughness,
                ior,
                transmission,
                thin,
                clearcoat,
                clearcoat_roughness,
                specular,
                specular_color,
            } => Bsdf::Pbr(
                Pbr::new(metallic as f32, roughness as f32, ior as f32)
                    .transmitting(transmission as f32)
                    .thin_walled(thin)
                    .coated(clearcoat as f32, clearcoat_roughness as f32)
                    .specular(
                        specular as f32,
                        DVec3::from_array(specular_color).as_vec3().into(),
                    ),
            ),
        };
        Self {
            bsdf,
            albedo: f32x3(m.albedo),
            emission: f32x3(m.emission),
            emissive: m.is_emissive(),
            maps: NO_MAPS,
            absorb: m.attenuation.map_or(Vec3A::ZERO, |a| {
                Vec3A::from(a.coefficient().as_vec3()).min(Vec3A::splat(f32::MAX))
            }),
        }
    }
}

/// A sampled continuation of a path.
#[derive(Clone, Copy, Debug)]
pub struct Scattered {
    pub dir: Vec3A,
    /// BSDF * cos / pdf.
    pub weight: Vec3A,
    /// A delta lobe: next-event estimation cannot reach it.
    pub specular: bool,
    /// Through the surface (refraction), not back off it.
    pub transmitted: bool,
    /// The density (solid angle) the direction was drawn with, where
    /// multiple importance sampling weighs it against next-event
    /// estimation (`pbr`); 0 elsewhere (a diffuse surface leaves emitters
    /// to next-event estimation alone; a delta lobe has no density).
    pub pdf: f32,
}

/// Mirror reflection of `d` about unit `n`.
#[inline(always)]
pub fn reflect(d: Vec3A, n: Vec3A) -> Vec3A {
    d - n * (2.0 * d.dot(n))
}

/// Cosine-weighted direction about unit `n`.
#[inline(always)]
pub fn cosine_hemisphere<V: Vector>(n: V, u1: V::R, u2: V::R) -> V {
    let c = <V::R as Real>::splat;
    let (sin, cos) = sincos_turns(u1);
    let r = u2.sqrt();
    let z = (c(1.0) - u2).max(c(0.0)).sqrt();
    let (t, b) = basis(n);
    t * (r * cos) + b * (r * sin) + n * z
}

/// Samples the continuation of a ray travelling along unit `d` that hit a
/// surface from outside (`entering`, by the geometric normal) or inside;
/// `nl` is the unit shading normal turned towards the side `d` came from.
#[inline(always)]
pub fn scatter(
    m: &SurfaceMaterial,
    d: Vec3A,
    entering: bool,
    nl: Vec3A,
    sampler: &mut Sampler,
) -> Scattered {
    scatter_with(m, d, entering, nl, sampler, Lobes::Build(None))
}

/// A `pbr` material's lobes for [`scatter_with`].
#[derive(Clone, Copy, Debug)]
pub enum Lobes<'a> {
    /// Built by next-event estimation for the same ray and normal (the
    /// same numbers either way: built once).
    Built(&'a ggx::Lobes),
    /// To build, the clear coat on its own unit normal where it has one
    /// (world space, on the side of the shading normal).
    Build(Option<Vec3A>),
}

/// [`scatter`] with a `pbr` material's [`Lobes`].
#[inline(always)]
pub fn scatter_with(
    m: &SurfaceMaterial,
    d: Vec3A,
    entering: bool,
    nl: Vec3A,
    sampler: &mut Sampler,
    lobes: Lobes,
) -> Scattered {
    match m.bsdf {
        Bsdf::Diffuse => {
            let (u1, u2) = sampler.bsdf_2d();
            Scattered {
                dir: cosine_hemisphere(nl, u1, u2),
                weight: m.albedo,
                specular: false,
                transmitted: false,
                pdf: 0.0,
            }
        }
        Bsdf::Mirror => Scattered {
            dir: reflect(d, nl),
            weight: m.albedo,
            specular: true,
            transmitted: false,
            pdf: 0.0,
        },
        Bsdf::Glass { ior, schlick } => {
            let (n1, n2) = if entering { (1.0, ior) } else { (ior, 1.0) };
            let cos_i = (-d.dot(nl)).clamp(0.0, 1.0);
            let split = if schlick {
                fresnel::schlick(cos_i, n1, n2)
            } else {
                fresnel::exact(cos_i, n1, n2)
            };
            let reflected = sampler.bsdf_choice() < split.reflectance;
            let dir = if reflected {
                reflect(d, nl)
            } else {
                let eta = n1 / n2;
                (d * eta + nl * (eta * cos_i - split.cos_t)).normalize()
            };
            Scattered {
                dir,
                weight: m.albedo,
                specular: true,
                transmitted: !reflected,
                pdf: 0.0,
            }
        }
        Bsdf::Pbr(p) => {
            let choice = sampler.bsdf_choice();
            let u = sampler.bsdf_2d();
            let (t, b) = basis(nl);
            let wo = Vec3A::new(-d.dot(t), -d.dot(b), -d.dot(nl));
            let tables = ggx::tables();
            let sampled = match lobes {
                Lobes::Built(l) => ggx::sample_from(tables, &p, m.albedo, l, wo, choice, u),
                Lobes::Build(None) => ggx::sample(tables, &p, m.albedo, (wo, entering), choice, u),
                Lobes::Build(Some(nc)) => {
                    let frame = ggx::coat::Frame::new(Vec3A::new(nc.dot(t), nc.dot(b), nc.dot(nl)));
                    let l = ggx::Lobes::framed(tables, &p, m.albedo, (wo, entering), Some(frame));
                    ggx::sample_from(tables, &p, m.albedo, &l, wo, choice, u)
                }
            };
            match sampled {
                // Normalised: inside a transmitting object a path may
                // bounce many times, and each frame's rounding would
                // otherwise grow the next hit's (and so the next frame's).
                Some(s) => Scattered {
                    dir: (t * s.wi.x + b * s.wi.y + nl * s.wi.z).normalize(),
                    weight: s.weight,
                    specular: false,
                    transmitted: s.wi.z < 0.0,
                    pdf: s.pdf,
                },
                // Below the surface: no contribution (the path ends on its
                // zero weight).
                None => Scattered {
                    dir: nl,
                    weight: Vec3A::ZERO,
                    specular: false,
                    transmitted: false,
                    pdf: 0.0,
                },
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_hemisphere_has_the_right_mean_cosine() {
        // E[cos] under p = cos/pi is 2/3.
        let n = Vec3A::new(0.2, -0.9, 0.3).normalize();
        let count = 100_000u64;
        let mut sum = 0.0f64;
        for i in 0..count {
            let mut s = Sampler::new(0, i, 0);
            let (u1, u2) = s.next_2d();
            let w = cosine_hemisphere(n, u1, u2);
            let c = w.dot(n);
            assert!(c >= -1e-6);
            sum += f64::from(c);
        }
        let mean = sum / count as f64;
        assert!((mean - 2.0 / 3.0).abs() < 3e-3, "mean cosine {mean}");
    }

    #[test]
    fn refraction_obeys_snell() {
        let m = SurfaceMaterial {
            bsdf: Bsdf::Glass {
                ior: 1.5,
                schlick: false,
            },
            albedo: Vec3A::ONE,
            emission: Vec3A::ZERO,
            emissive: false,
            maps: NO_MAPS,
            absorb: Vec3A::ZERO,
        };
        let d = Vec3A::new(0.6, -0.8, 0.0);
        let n = Vec3A::Y;
        for i in 0..64 {
            let mut s = Sampler::new(0, i, 0);
            let out = scatter(&m, d, true, n, &mut s);
            assert_eq!(out.transmitted, out.dir.y < 0.0);
            if out.dir.y < 0.0 {
                let sin_t = out.dir.x;
                assert!((sin_t * 1.5 - 0.6).abs() < 1e-5, "Snell: {sin_t}");
            } else {
                assert!((out.dir - Vec3A::new(0.6, 0.8, 0.0)).length() < 1e-6);
            }
        }
    }
}
