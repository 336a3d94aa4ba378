//! Every kernel variant builds, and the generic program renders what the
//! specialised one does.

use super::*;

#[test]
fn every_feature_combination_builds() {
    let Some(_) = device() else { return };
    use pathstream::render::backend::opencl::{Features, ProgramKey};
    let mut keys = Vec::new();
    // (spheres, quads, meshes); with meshes, diffuse alone or every material.
    for shapes in [
        (true, false, false),
        (false, true, false),
        (true, true, false),
        (false, false, true),
        (true, true, true),
    ] {
        for materials in 1u8..8 {
            if shapes.2 && materials != 1 && materials != 7 {
                continue;
            }
            let (diffuse, mirror, glass) =
                (materials & 1 != 0, materials & 2 != 0, materials & 4 != 0);
            let fresnels: &[(bool, bool)] = if glass {
                &[(true, false), (false, true), (true, true)]
            } else {
                &[(false, false)]
            };
            for &(schlick, exact) in fresnels {
                for lights in 0u8..4 {
                    keys.push(ProgramKey::Specialised(Features {
                        spheres: shapes.0,
                        quads: shapes.1,
                        diffuse,
                        mirror,
                        glass,
                        // Half the combinations with the metallic-roughness code.
                        ggx: lights % 2 == 1,
                        // Rough glass with half of those.
                        transmission: lights == 3,
                        // Absorption inside with glass or rough glass.
                        volume: (glass && lights == 0) || lights == 3,
                        // A clear coat with the metallic-roughness code,
                        // with and without rough glass.
                        coat: lights % 2 == 1 && materials % 2 == 1,
                        // Its own normal where textures are in too.
                        coat_normal: lights == 1 && materials % 2 == 1,
                        // Vertex colours with meshes, half the time.
                        vertex_colors: shapes.2 && lights % 2 == 0,
                        schlick,
                        exact,
                        sphere_lights: lights & 1 != 0,
                        quad_lights: lights & 2 != 0,
                        nee: lights != 0,
                        box_filter: lights == 3,
                        sobol: lights != 1,
                        num_objects: 3,
                        num_lights: u32::from(lights != 0),
                        max_depth: u32::from(materials),
                        // With and without the BVH code (always with meshes).
                        bvh_stack: if lights % 2 == 0 || shapes.2 {
                            3 * u32::from(materials) + 4
                        } else {
                            0
                        },
                        mesh_stack: if shapes.2 { 40 } else { 0 },
                        tri_lights: shapes.2 && lights & 1 != 0,
                        environment: shapes.2 && lights & 2 != 0,
                        // An environment map where there are no meshes and
                        // there is a light (with and without MAT_PBR).
                        env_map: !shapes.2 && lights & 2 != 0,
                        // A sky's sun with half the maps.
                        sun: !shapes.2 && lights & 2 != 0 && materials % 2 == 1,
                        // A thin lens in half the combinations.
                        lens: materials % 2 == 0,
                        // Each projection (perspective most often).
                        projection: u32::from(materials % 3 == 1) * (1 + u32::from(lights) % 2),
                        // The denoiser's features with a third.
                        features: materials % 3 == 2,
                        // Texture maps with a quarter (every material kind).
                        textures: lights == 1 || (lights == 2 && materials == 3),
                        // Alpha tests with meshes, with and without textures.
                        alpha: shapes.2 && lights <= 1,
                        inject_nan_every: None,
                    }));
                }
            }
        }
    }
    keys.push(ProgramKey::Generic {
        inject_nan_every: None,
        features: true,
    });
    assert_eq!(keys.len(), 3 * 15 * 4 + 2 * 4 * 4 + 1);
    // Two threads, each with its own context: the compiler is the slow part.
    let failures: Vec<String> = std::thread::scope(|scope| {
        let halves: Vec<_> = keys
            .chunks(keys.len().div_ceil(2))
            .map(|chunk| {
                scope.spawn(move || {
                    let d = OpenClBackend::new(None).expect("device");
                    chunk
                        .iter()
                        .filter_map(|k| {
                            d.build_sources(&SOURCES, &k.build_options())
                                .err()
                                .map(|e| format!("{k:?}: {e}"))
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        halves
            .into_iter()
            .flat_map(|h| h.join().expect("thread"))
            .collect()
    });
    assert!(
        failures.is_empty(),
        "{} programs failed to build:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn the_generic_program_renders_what_the_specialised_one_does() {
    let Some(mut specialised) = device() else {
        return;
    };
    let mut generic = OpenClBackend::new(None).expect("device");
    generic.generic = true;
    for name in ["cornell", "cornell-glass", "cornell-quads"] {
        let job = RenderJob::new(
            &scene(name),
            16,
            16,
            &Quality {
                seed: 5,
                ..Quality::default()
            },
        );
        let (mut a, mut b) = (Film::new(16, 16), Film::new(16, 16));
        specialised.render(&job, &mut a, 16).expect("render");
        generic.render(&job, &mut b, 16).expect("render");
        // The same samples along the same paths: pixel for pixel equal, to
        // the rounding that compiling two programs may differ in.
        let (ma, mb) = (a.mean(), b.mean());
        let close = ma
            .iter()
            .zip(&mb)
            .filter(|(x, y)| {
                (0..3).all(|c| (x[c] - y[c]).abs() <= 1e-4 * x[c].abs().max(y[c].abs()).max(1e-3))
            })
            .count();
        eprintln!("{name}: {close} of 256 pixels equal to 1e-4");
        assert!(close >= 240, "{name}: only {close} of 256 pixels agree between the specialised and the generic program");
        assert_agree(
            &a,
            &b,
            8,
            4.5,
            1e-4,
            &format!("{name}: specialised vs generic program"),
        );
    }
}
