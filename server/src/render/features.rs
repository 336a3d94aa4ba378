//! Feature buffers: what a denoiser is guided by. Per pixel, the mean over
//! its samples of the albedo and the shading normal where each camera path
//! first meets a surface that is not a perfect mirror or smooth glass (Open
//! Image Denoise's recommendation: through specular surfaces to what they
//! show, tinted by them).
//!
//! A path finds its guide ([`Guide`]) as it goes (`integrator`); a film
//! keeps the sums ([`FeatureSums`]) beside its radiance only for jobs that
//! ask for them (`PathSettings::features`), so a render that is never
//! denoised pays for neither. Where a path leaves the scene, the albedo is
//! what it sees of the environment (each channel at most 1) and the normal
//! is zero; where it meets an emitter, the emission at most 1.

use crate::render::math::Vec3A;

/// The first non-specular hit of one path, as a denoiser wants it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Guide {
    /// Albedo, tinted by the mirrors and glass the path went through.
    pub albedo: Vec3A,
    /// Unit shading normal on the side the path came from (world space);
    /// zero where the path left the scene.
    pub normal: Vec3A,
}

/// A guide's value for light that is seen directly: at most 1 per channel.
#[inline(always)]
pub fn light_albedo(radiance: Vec3A) -> Vec3A {
    radiance.clamp(Vec3A::ZERO, Vec3A::ONE)
}

/// Sums of one pixel's guides (f32: they are bounded, and a denoiser needs
/// nothing like the radiance's precision).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Zeroable, bytemuck::Pod)]
#[repr(C)]
pub struct FeatureSums {
    pub albedo: [f32; 3],
    pub normal: [f32; 3],
}

impl FeatureSums {
    /// Adds one path's guide.
    #[inline(always)]
    pub fn add(&mut self, g: &Guide) {
        for (s, v) in self.albedo.iter_mut().zip(g.albedo.to_array()) {
            *s += v;
        }
        for (s, v) in self.normal.iter_mut().zip(g.normal.to_array()) {
            *s += v;
        }
    }

    /// Adds another pixel's sums (of other samples).
    #[inline(always)]
    pub fn absorb(&mut self, other: &FeatureSums) {
        for c in 0..3 {
            self.albedo[c] += other.albedo[c];
            self.normal[c] += other.normal[c];
        }
    }
}

/// A film's feature images: the mean albedo and normal of every pixel,
/// row-major, top row first, as a denoiser reads them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Features {
    pub width: u32,
    pub height: u32,
    pub albedo: Vec<[f32; 3]>,
    pub normal: Vec<[f32; 3]>,
}

/// Pixels `range` of a film's feature sums split into chunks of `chunk`
/// pixels: one entry per chunk of the radiance's `range`, `None` for each
/// where the film keeps no features (`sums` empty), so that the backends
/// zip them with the radiance's chunks.
pub fn chunks(
    sums: &mut [FeatureSums],
    range: std::ops::Range<usize>,
    chunk: usize,
) -> Vec<Option<&mut [FeatureSums]>> {
    let chunk = chunk.max(1);
    if sums.is_empty() {
        (0..range.len().div_ceil(chunk)).map(|_| None).collect()
    } else {
        sums[range].chunks_mut(chunk).map(Some).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_add_guides_and_other_sums() {
        let mut a = FeatureSums::default();
        let g = Guide {
            albedo: Vec3A::new(0.5, 0.25, 1.0),
            normal: Vec3A::new(0.0, 0.0, -1.0),
        };
        a.add(&g);
        a.add(&g);
        let mut b = FeatureSums::default();
        b.add(&g);
        a.absorb(&b);
        assert_eq!(a.albedo, [1.5, 0.75, 3.0]);
        assert_eq!(a.normal, [0.0, 0.0, -3.0]);
    }

    #[test]
    fn chunks_match_the_radiance_chunks() {
        let mut none: Vec<FeatureSums> = Vec::new();
        assert_eq!(chunks(&mut none, 0..10, 4).len(), 3);
        assert_eq!(chunks(&mut none, 3..10, 4).len(), 2);
        let mut some = vec![FeatureSums::default(); 10];
        let c = chunks(&mut some, 0..10, 4);
        assert_eq!(c.len(), 3);
        assert_eq!(c[2].as_ref().map(|s| s.len()), Some(2));
        let c = chunks(&mut some, 3..10, 4);
        assert_eq!(
            c.iter()
                .map(|c| c.as_ref().map_or(0, |s| s.len()))
                .collect::<Vec<_>>(),
            [4, 3]
        );
    }

    #[test]
    fn light_is_seen_as_an_albedo_of_at_most_one() {
        let a = light_albedo(Vec3A::new(17.0, 0.5, -1.0));
        assert_eq!(a, Vec3A::new(1.0, 0.5, 0.0));
    }
}
