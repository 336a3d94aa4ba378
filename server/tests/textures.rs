//! Texture maps rendered, on every backend: generated `.glb` files (a quad
//! with a checkerboard, metallic-roughness and normal maps) placed in
//! scenes whose images are known in closed form or equal to an untextured
//! twin's.
//!
//! - A checkerboard on a mirror in a white sky: each check shows exactly its
//!   texel's sRGB-decoded colour (a mirror reflects the sky's 1 times its
//!   tint, with no noise); wrap modes, `KHR_texture_transform` and UV set 1
//!   put the checks where their closed form says.
//! - A metallic-roughness texture renders as the constant material with
//!   the texel's values; a flat normal map as no map.
//! - A normal map tilted towards a light brightens the quad, away from it
//!   darkens it; given and generated (MikkTSpace) tangents agree.
//! - An emission map glows as its texels (noise-free, black sky and base),
//!   and lights a floor as it glows: shadow rays read it (NEE on and off
//!   agree; a uniform map equals the emission it scales).
//! - A hand-written scene names PNG files in its materials' fields: a
//!   checkerboard albedo shows as the `.glb`'s does, metallic and
//!   roughness textures render as the constant twin, and the scene writes
//!   the texture names back (and validates again to itself).
//! - The kernel's map routines (lookups, wraps, transforms, sRGB, the
//!   metallic-roughness, normal and emission maps) give the CPU's floats
//!   bit for bit.

mod common;
mod parity;

use common::{assert_agree, backends, region, render_on};
use pathstream::model::write_glb::{glb, GlbMaterial, GlbTexture};
use pathstream::model::{MeshData, Wrap};
use pathstream::render::texture::srgb_table;
use pathstream::render::{Backend, Film, Quality, Scene};
use serde_json::{json, Value};

/// A 2 x 2 quad in the z = 0 plane facing +z, UV set `set` covering the
/// image once, upright (u along +x, v down); the other set constant.
fn quad(set: usize) -> MeshData {
    let uv = vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let mut uvs = [Some(vec![[0.5, 0.5]; 4]), Some(vec![[0.5, 0.5]; 4])];
    uvs[set] = Some(uv);
    MeshData {
        name: "quad".into(),
        positions: vec![
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ],
        normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
        uvs,
        tangents: None,
        colors: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![0, 0],
    }
}

/// The sRGB bytes of check (i, j) of a 4 x 4 board (i across, j down).
fn check(i: usize, j: usize) -> [u8; 3] {
    [
        (40 + 60 * i) as u8,
        (30 + 70 * j) as u8,
        (200 - 40 * i - 20 * j) as u8,
    ]
}

/// An 8 x 8 texture: 4 x 4 checks of 2 x 2 texels, so that around each
/// check's centre a bilinear lookup reads only that check.
fn checkerboard() -> GlbTexture {
    let mut rgba = Vec::new();
    for y in 0..8 {
        for x in 0..8 {
            let [r, g, b] = check(x / 2, y / 2);
            rgba.extend([r, g, b, 255]);
        }
    }
    GlbTexture::new(8, 8, rgba)
}

/// A scene of `model` (a .glb written beside it) seen by an orthographic
/// camera that the quad fills, with `extra` objects and materials.
fn scene_with(dir: &tempfile::TempDir, model: &[u8], environment: Value, extra: Value) -> Scene {
    // A new name each time: the file cache knows a path by its size and time.
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let name = format!(
        "model{}.glb",
        NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    );
    std::fs::write(dir.path().join(&name), model).expect("glb");
    let mut objects = vec![json!({"type": "model", "file": name})];
    objects.extend(extra["objects"].as_array().cloned().unwrap_or_default());
    let doc = json!({
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 40, "projection": "orthographic", "ortho_height": 2},
        "environment": environment,
        "materials": extra.get("materials").cloned().unwrap_or(json!({})),
        "objects": objects,
    });
    let file = dir.path().join("scene.json");
    std::fs::write(&file, doc.to_string()).expect("scene");
    pathstream::resolve::load_scene(file.to_str().expect("utf-8")).expect("loads")
}

/// A mirror (metallic 1, roughness 0) tinted by `texture`.
fn mirror_with(texture: GlbTexture, set: usize) -> Vec<u8> {
    glb(
        &quad(set),
        &GlbMaterial {
            metallic: 1.0,
            roughness: 0.0,
            base_color_texture: Some(texture),
            ..GlbMaterial::default()
        },
    )
}

fn quality() -> Quality {
    Quality {
        seed: 7,
        ..Quality::default()
    }
}

/// The linear colour of check `c`.
fn linear(c: [u8; 3]) -> [f64; 3] {
    c.map(|b| f64::from(srgb_table()[b as usize]))
}

/// Asserts the mean of pixels `xs` x `ys` is `want` to rounding.
fn assert_colour(
    film: &Film,
    xs: std::ops::Range<u32>,
    ys: std::ops::Range<u32>,
    want: [f64; 3],
    what: &str,
) {
    let got = region(film, xs.clone(), ys.clone()).mean;
    for c in 0..3 {
        assert!(
            (got[c] - want[c]).abs() < 1e-5,
            "{what}: pixels {xs:?} x {ys:?}: {got:?}, not {want:?}"
        );
    }
}

#[test]
fn a_checkerboard_shows_each_check_where_the_closed_form_says() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = scene_with(
        &dir,
        &mirror_with(checkerboard(), 0),
        json!([1, 1, 1]),
        json!({}),
    );
    assert_checks(&scene, 1.0, "check");
}

/// Renders `scene` (a 64 x 64 view filled by the checkerboard) on every
/// backend and asserts that each check shows its colour times `scale`.
fn assert_checks(scene: &Scene, scale: f64, what: &str) {
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, scene, 64, 64, &quality(), 4);
        // 16 pixels per check; around each centre (16 i + 8) a bilinear
        // lookup reads that check alone for 4 pixels each way.
        for j in 0..4u32 {
            for i in 0..4u32 {
                let (x, y) = (16 * i + 7, 16 * j + 7);
                let want = linear(check(i as usize, j as usize)).map(|c| scale * c);
                let what = format!("{name}: {what} ({i}, {j})");
                assert_colour(&film, x..x + 2, y..y + 2, want, &what);
            }
        }
    }
}

#[test]
fn wrap_modes_transforms_and_uv_set_1_place_the_checks() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (wrap, right_half) in [
        // Check column k of the right half (u from 1 to 2) shows:
        (Wrap::Repeat, [0, 1, 2, 3]),
        (Wrap::Clamp, [3, 3, 3, 3]),
        (Wrap::Mirror, [3, 2, 1, 0]),
    ] {
        let mut t = checkerboard();
        t.wrap = [wrap, Wrap::Clamp];
        t.tex_coord = 1;
        // u doubled: the quad shows the image twice across.
        t.transform = Some(([0.0, 0.0], 0.0, [2.0, 1.0]));
        let scene = scene_with(&dir, &mirror_with(t, 1), json!([1, 1, 1]), json!({}));
        for (name, mut backend) in backends() {
            let film = render_on(&mut backend, &scene, 128, 128, &quality(), 2);
            for j in 0..4u32 {
                for k in 0..8u32 {
                    // Each check is 16 pixels wide and 32 high here.
                    let (x, y) = (16 * k + 7, 32 * j + 15);
                    let i = if k < 4 {
                        k as usize
                    } else {
                        right_half[k as usize - 4]
                    };
                    let want = linear(check(i, j as usize));
                    let what = format!("{name}: {wrap:?}: column {k}, row {j}");
                    assert_colour(&film, x..x + 2, y..y + 2, want, &what);
                }
            }
        }
    }
}

/// A light off to the quad's +x side (an emissive quad facing it at 45
/// degrees), the quad itself as `material` says, a black sky.
fn lit(dir: &tempfile::TempDir, material: GlbMaterial, tangents: bool) -> Scene {
    let mut mesh = quad(0);
    if tangents {
        mesh.tangents = Some(vec![[1.0, 0.0, 0.0, 1.0]; 4]);
    }
    lit_mesh(dir, material, &mesh)
}

fn lit_mesh(dir: &tempfile::TempDir, material: GlbMaterial, mesh: &MeshData) -> Scene {
    let extra = json!({
        "materials": {"lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [8, 8, 8]}},
        "objects": [{"type": "quad", "corner": [3, -1, 1], "edge_u": [0, 2, 0], "edge_v": [-1, 0, 1], "material": "lamp"}],
    });
    scene_with(dir, &glb(mesh, &material), json!([0, 0, 0]), extra)
}

/// The whole image's mean red on `backend`.
fn brightness(backend: &mut Backend, scene: &Scene) -> (f64, f64) {
    let film = render_on(backend, scene, 24, 24, &quality(), 64);
    let r = region(&film, 0..24, 0..24);
    (r.mean[0], r.var[0].sqrt())
}

#[test]
fn a_normal_map_tilts_towards_the_tangent_and_tangents_agree() {
    let dir = tempfile::tempdir().expect("tempdir");
    let diffuse = |normal: Option<[u8; 3]>| GlbMaterial {
        metallic: 0.0,
        roughness: 1.0,
        base_color: [0.8, 0.8, 0.8, 1.0],
        normal_texture: normal.map(|[r, g, b]| GlbTexture::new(1, 1, vec![r, g, b, 255])),
        ..GlbMaterial::default()
    };
    // 45 degrees towards +u (+x, the light's side) and away from it.
    let (towards, away) = ([218, 128, 218], [37, 128, 218]);
    for (name, mut backend) in backends() {
        let flat = brightness(&mut backend, &lit(&dir, diffuse(None), false));
        let up = brightness(&mut backend, &lit(&dir, diffuse(Some(towards)), false));
        let down = brightness(&mut backend, &lit(&dir, diffuse(Some(away)), false));
        eprintln!("{name}: away {down:?}, flat {flat:?}, towards {up:?}");
        let apart = |a: (f64, f64), b: (f64, f64)| (b.0 - a.0) / (a.1 * a.1 + b.1 * b.1).sqrt();
        assert!(
            apart(flat, up) > 8.0,
            "{name}: tilted towards the light: {up:?} vs flat {flat:?}"
        );
        assert!(
            apart(down, flat) > 8.0,
            "{name}: tilted away: {down:?} vs flat {flat:?}"
        );
        // The file's tangents (+x) and MikkTSpace's agree.
        let given = brightness(&mut backend, &lit(&dir, diffuse(Some(towards)), true));
        assert!(
            apart(given, up).abs() < 4.0,
            "{name}: given {given:?} vs generated {up:?}"
        );
    }
}

#[test]
fn maps_render_as_their_constant_twins() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pbr = |mr: Option<[u8; 3]>, metallic: f64, roughness: f64, normal: bool| GlbMaterial {
        base_color: [0.9, 0.7, 0.5, 1.0],
        metallic,
        roughness,
        metallic_roughness_texture: mr.map(|[r, g, b]| GlbTexture::new(1, 1, vec![r, g, b, 255])),
        normal_texture: normal.then(|| GlbTexture::new(1, 1, vec![128, 128, 255, 255])),
        ..GlbMaterial::default()
    };
    // Red is not read: metal from blue (0.8), roughness from green (0.4).
    // "Flat" (128, 128, 255) is (1/255, 1/255, 1) in the tangent frame (+x,
    // +y, +z here), which the twin's vertex normals give instead.
    let textured = lit(&dir, pbr(Some([255, 102, 204]), 1.0, 1.0, true), false);
    let mut tilted = quad(0);
    let e = 2.0 * 128.0 / 255.0 - 1.0;
    let l = (2.0 * e * e + 1.0f32).sqrt();
    tilted.normals = Some(vec![[e / l, e / l, 1.0 / l]; 4]);
    let constant = lit_mesh(
        &dir,
        pbr(None, 204.0 / 255.0, 102.0 / 255.0, false),
        &tilted,
    );
    for (name, mut backend) in backends() {
        let a = render_on(&mut backend, &textured, 24, 24, &quality(), 64);
        let b = render_on(&mut backend, &constant, 24, 24, &quality(), 64);
        assert_agree(
            &a,
            &b,
            6,
            4.5,
            1e-4,
            &format!("{name}: metallic-roughness map vs factors"),
        );
    }
}

/// A black quad glowing with `emissive` times `texture`.
fn glowing(emissive: f64, texture: GlbTexture) -> Vec<u8> {
    let material = GlbMaterial {
        base_color: [0.0, 0.0, 0.0, 1.0],
        metallic: 0.0,
        emissive: [emissive; 3],
        emissive_texture: Some(texture),
        ..GlbMaterial::default()
    };
    glb(&quad(0), &material)
}

#[test]
fn an_emission_map_glows_as_its_texels() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = scene_with(
        &dir,
        &glowing(2.0, checkerboard()),
        json!([0, 0, 0]),
        json!({}),
    );
    assert_checks(&scene, 2.0, "glowing check");
}

/// A white floor lit by `model` (a glowing quad) held face down above it,
/// with a second, plain lamp off to the side (so that the pick between
/// them weighs the map's mean), in a black sky.
fn floor_under(dir: &tempfile::TempDir, model: &[u8], name: &str) -> Scene {
    std::fs::write(dir.path().join(name), model).expect("glb");
    let doc = json!({
        "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "vfov_deg": 50},
        "materials": {
            "white": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]},
            "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [0.5, 0.5, 0.5]},
        },
        "objects": [
            {"type": "quad", "corner": [-2, 0, -2], "edge_u": [0, 0, 4], "edge_v": [4, 0, 0], "material": "white"},
            {"type": "model", "file": name,
             "transform": {"translate": [0, 1.2, 0], "rotate": {"axis": [1, 0, 0], "deg": 90}}},
            {"type": "sphere", "center": [-2.5, 1, -1], "radius": 0.3, "material": "lamp"},
        ],
    });
    let file = dir.path().join(format!("{name}.json"));
    std::fs::write(&file, doc.to_string()).expect("scene");
    pathstream::resolve::load_scene(file.to_str().expect("utf-8")).expect("loads")
}

#[test]
fn shadow_rays_read_the_emission_map() {
    let dir = tempfile::tempdir().expect("tempdir");
    let checks = floor_under(&dir, &glowing(4.0, checkerboard()), "checks.glb");
    // A uniform map of grey g glows as the plain emission 4 g.
    let g = 150u8;
    let grey = floor_under(
        &dir,
        &glowing(4.0, GlbTexture::new(1, 1, vec![g, g, g, 255])),
        "grey.glb",
    );
    let e = 4.0 * f64::from(srgb_table()[g as usize]);
    let plain = GlbMaterial {
        base_color: [0.0, 0.0, 0.0, 1.0],
        metallic: 0.0,
        emissive: [e; 3],
        ..GlbMaterial::default()
    };
    let plain = floor_under(&dir, &glb(&quad(0), &plain), "plain.glb");
    let nee_off = Quality {
        nee: false,
        ..quality()
    };
    for (name, mut backend) in backends() {
        let on = render_on(&mut backend, &checks, 24, 24, &quality(), 256);
        let off = render_on(&mut backend, &checks, 24, 24, &nee_off, 1024);
        assert_agree(&on, &off, 6, 4.5, 1e-4, &format!("{name}: NEE on vs off"));
        let a = render_on(&mut backend, &grey, 24, 24, &quality(), 64);
        let b = render_on(&mut backend, &plain, 24, 24, &quality(), 64);
        assert_agree(&a, &b, 6, 4.5, 1e-4, &format!("{name}: grey map vs plain"));
    }
}

/// `rgba` (`w` x `h`) written as a PNG file at `path`.
fn write_png(path: &std::path::Path, w: u32, h: u32, rgba: &[u8]) {
    image::save_buffer(path, rgba, w, h, image::ExtendedColorType::Rgba8).expect("png");
}

#[test]
fn scene_json_materials_name_their_textures() {
    let dir = tempfile::tempdir().expect("tempdir");
    let board = checkerboard();
    write_png(&dir.path().join("check.png"), 8, 8, &board.rgba);
    write_png(&dir.path().join("mr.png"), 1, 1, &[255, 102, 204, 255]);
    let quad = |material: &str| json!({"type": "quad", "corner": [-1, -1, 0], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0], "material": material});
    let load = |doc: Value| {
        let file = dir.path().join("scene.json");
        std::fs::write(&file, doc.to_string()).expect("scene");
        pathstream::resolve::load_scene(file.to_str().expect("utf-8")).expect("loads")
    };
    let camera = json!({"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 40,
        "projection": "orthographic", "ortho_height": 2});
    let tiles = load(json!({
        "camera": camera,
        "environment": [1, 1, 1],
        "materials": {"tiles": {"type": "mirror", "albedo": {"texture": "check.png"}}},
        "objects": [quad("tiles")],
    }));
    assert_checks(&tiles, 1.0, "scene JSON check");

    // Metal from blue (0.8), roughness from green (0.4) times its factor.
    let lit = |material: Value| {
        load(json!({
            "camera": camera,
            "materials": {"m": material,
                "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [8, 8, 8]}},
            "objects": [quad("m"),
                {"type": "quad", "corner": [3, -1, 1], "edge_u": [0, 2, 0], "edge_v": [-1, 0, 1], "material": "lamp"}],
        }))
    };
    let textured = lit(json!({"type": "pbr", "base_color": [0.9, 0.7, 0.5],
        "metallic": {"texture": "mr.png"},
        "roughness": {"texture": "mr.png", "factor": 0.5},
        "normal": {"texture": "check.png", "scale": 0}}));
    let twin = lit(json!({"type": "pbr", "base_color": [0.9, 0.7, 0.5],
        "metallic": 204.0 / 255.0, "roughness": 0.5 * 102.0 / 255.0}));
    for (name, mut backend) in backends() {
        let a = render_on(&mut backend, &textured, 24, 24, &quality(), 64);
        let b = render_on(&mut backend, &twin, 24, 24, &quality(), 64);
        let what = format!("{name}: scene JSON metallic-roughness texture vs factors");
        assert_agree(&a, &b, 6, 4.5, 1e-4, &what);
    }

    // Written back by name, and valid again as the same scene.
    let json = serde_json::to_value(textured.to_json()).expect("json");
    assert_eq!(
        json["materials"]["m"]["roughness"],
        json!({"texture": "mr.png", "factor": 0.5}),
        "{json}"
    );
    assert_eq!(
        json["materials"]["m"]["normal"],
        json!({"texture": "check.png", "scale": 0.0}),
        "{json}"
    );
    let again = textured
        .revalidate(&textured.to_json())
        .expect("valid again");
    assert_eq!(again, textured);
}

/// A texture of `w` x `h` texels of hashed bytes.
fn noise(w: u32, h: u32, salt: u64) -> GlbTexture {
    let rgba = (0..u64::from(w * h) * 4)
        .map(|i| (parity::uniform(i, salt) * 256.0) as u8)
        .collect();
    GlbTexture::new(w, h, rgba)
}

#[test]
fn the_kernels_map_routines_agree_with_the_cpus_bit_for_bit() {
    let Some(d) = common::opencl_device() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let mut base = checkerboard();
    base.wrap = [Wrap::Mirror, Wrap::Repeat];
    base.transform = Some(([0.25, -0.5], 0.7, [1.5, -2.0]));
    let mut mr = noise(5, 3, 1);
    mr.tex_coord = 1;
    mr.wrap = [Wrap::Clamp, Wrap::Mirror];
    let material = GlbMaterial {
        base_color: [0.9, 0.8, 0.7, 1.0],
        metallic: 0.75,
        roughness: 0.5,
        base_color_texture: Some(base),
        metallic_roughness_texture: Some(mr),
        normal_texture: Some(noise(4, 4, 2)),
        normal_scale: 0.8,
        emissive: [2.0, 1.5, 0.5],
        emissive_texture: Some(noise(3, 2, 3)),
        ..GlbMaterial::default()
    };
    let scene = scene_with(&dir, &glb(&quad(0), &material), json!([1, 1, 1]), json!({}));
    let job = pathstream::render::RenderJob::new(&scene, 8, 8, &quality());
    parity::assert_maps_agree(&d, &job, 20_000);
}
