//! glTF texture maps: a generated `.glb` with base colour,
//! metallic-roughness and normal textures read back exactly (images,
//! samplers, UV sets, transforms, tangents given or generated); broken
//! images and references fail with the element named.

use crate::model::write_glb::{glb, GlbMaterial, GlbTexture};
use crate::model::{load_bytes, Limits, MeshData, Wrap};

/// A unit quad facing +z with UVs covering the image once.
pub(crate) fn quad() -> MeshData {
    MeshData {
        name: "quad".into(),
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
        uvs: [
            Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
            Some(vec![[0.5; 2]; 4]),
        ],
        tangents: None,
        colors: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![0, 0],
    }
}

fn checker() -> GlbTexture {
    let mut rgba = Vec::new();
    for y in 0..4u8 {
        for x in 0..4u8 {
            rgba.extend([x * 60, y * 60, 255 - x * 60, 255]);
        }
    }
    GlbTexture::new(4, 4, rgba)
}

#[test]
fn maps_images_and_attributes_are_read() {
    let mut base = checker();
    base.wrap = [Wrap::Mirror, Wrap::Clamp];
    base.transform = Some(([0.5, 0.25], 0.5, [2.0, 3.0]));
    let mut mr = GlbTexture::new(1, 1, vec![0, 128, 255, 255]);
    mr.tex_coord = 1;
    let material = GlbMaterial {
        metallic: 0.5,
        roughness: 0.25,
        base_color_texture: Some(base),
        metallic_roughness_texture: Some(mr),
        normal_texture: Some(GlbTexture::new(1, 1, vec![128, 128, 255, 255])),
        normal_scale: 0.5,
        emissive: [4.0, 2.0, 1.0],
        emissive_texture: Some(GlbTexture::new(1, 1, vec![10, 20, 30, 255])),
        ..GlbMaterial::default()
    };
    let bytes = glb(&quad(), &material);
    let model = load_bytes(&bytes, "t.glb", &Limits::default()).expect("loads");
    assert_eq!(model.images.len(), 4);
    assert_eq!(model.images[3].rgba, [10, 20, 30, 255]);
    assert_eq!((model.images[0].width, model.images[0].height), (4, 4));
    assert_eq!(model.images[0].rgba, checker().rgba);
    assert_eq!(model.images[1].rgba, [0, 128, 255, 255]);
    let (_, _, maps) = &model.materials[0];
    let b = maps.base_color.expect("base colour");
    assert_eq!((b.image, b.uv, b.wrap), (0, 0, [Wrap::Mirror, Wrap::Clamp]));
    assert_eq!(
        (b.offset, b.rotation, b.scale),
        ([0.5, 0.25], 0.5, [2.0, 3.0])
    );
    let m = maps.metallic.expect("metallic-roughness");
    assert_eq!((m.image, m.uv, m.wrap), (1, 1, [Wrap::Repeat; 2]));
    assert_eq!(maps.roughness, Some(m), "one texture, both slots");
    assert_eq!(maps.normal.map(|n| n.image), Some(2));
    assert_eq!(maps.normal_scale, 0.5);
    assert_eq!(maps.emission.map(|e| e.image), Some(3));
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
    let mesh = &model.meshes[0];
    assert_eq!(mesh.uvs, quad().uvs);
    // No TANGENT in the file: MikkTSpace's, along +x (u), for a normal map.
    let t = mesh.tangents.as_ref().expect("generated tangents");
    assert_eq!(t.len(), mesh.positions.len());
    for v in t {
        assert!((v[0] - 1.0).abs() < 1e-5 && v[3] == 1.0, "{v:?}");
    }
    // The material stays pbr with its factors (its map reads the rest),
    // its emission the factor times KHR_materials_emissive_strength.
    assert!(matches!(
        model.materials[0].1,
        crate::model::Material::Pbr { metallic, roughness, emission: Some([4.0, 2.0, 1.0]), .. }
            if metallic == 0.5 && roughness == 0.25
    ));
}

#[test]
fn given_tangents_are_kept_and_untextured_meshes_get_none() {
    let mut mesh = quad();
    mesh.tangents = Some(vec![[0.0, 1.0, 0.0, -1.0]; 4]);
    let material = GlbMaterial {
        normal_texture: Some(GlbTexture::new(1, 1, vec![128, 128, 255, 255])),
        ..GlbMaterial::default()
    };
    let model = load_bytes(&glb(&mesh, &material), "t.glb", &Limits::default()).expect("loads");
    assert_eq!(model.meshes[0].tangents, mesh.tangents);
    let model = load_bytes(
        &glb(&quad(), &GlbMaterial::default()),
        "t.glb",
        &Limits::default(),
    )
    .expect("loads");
    assert!(model.meshes[0].tangents.is_none());
    assert!(model.images.is_empty());
}

/// Loads `bytes`, which must fail; the error text.
fn error(bytes: &[u8], limits: &Limits) -> String {
    match load_bytes(bytes, "t.glb", limits) {
        Ok(_) => panic!("loaded"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn broken_images_are_named() {
    let material = GlbMaterial {
        base_color_texture: Some(checker()),
        ..GlbMaterial::default()
    };
    let bytes = glb(&quad(), &material);
    // Truncate the PNG in the binary chunk: find its signature.
    let sig = b"\x89PNG\r\n\x1a\n";
    let at = bytes
        .windows(8)
        .position(|w| w == sig)
        .expect("png in the glb");
    let mut cut = bytes.clone();
    // Overwrite the PNG's IHDR data and beyond with zeros.
    for b in &mut cut[at + 20..at + 60] {
        *b = 0;
    }
    let e = error(&cut, &Limits::default());
    assert!(e.contains("images[0]"), "{e}");
    // A 100000 x 100000 header: refused before decoding.
    let mut huge = bytes.clone();
    huge[at + 16..at + 20].copy_from_slice(&100_000u32.to_be_bytes());
    huge[at + 20..at + 24].copy_from_slice(&100_000u32.to_be_bytes());
    let crc = crc32fast::hash(&huge[at + 12..at + 29]);
    huge[at + 29..at + 33].copy_from_slice(&crc.to_be_bytes());
    let e = error(&huge, &Limits::default());
    assert!(e.contains("images[0]") && e.contains("100000"), "{e}");
    // The texel budget counts every image.
    let limits = Limits {
        max_texels: 15,
        ..Limits::default()
    };
    let e = error(&bytes, &limits);
    assert!(e.contains("16 texels") && e.contains("limit of 15"), "{e}");
    // Not an image at all.
    let mut junk = bytes.clone();
    junk[at..at + 8].copy_from_slice(b"JUNKJUNK");
    let e = error(&junk, &Limits::default());
    assert!(
        e.contains("images[0]") && e.contains("not a PNG or JPEG"),
        "{e}"
    );
}

#[test]
fn texture_references_out_of_range_are_named() {
    let material = GlbMaterial {
        base_color_texture: Some(checker()),
        ..GlbMaterial::default()
    };
    let bytes = glb(&quad(), &material);
    // Point the material at texture 7 (the JSON chunk is plain text).
    let text = String::from_utf8_lossy(&bytes).into_owned();
    let needle = "\"baseColorTexture\":{\"index\":0";
    assert!(text.contains(needle), "writer changed");
    let at = bytes
        .windows(needle.len())
        .position(|w| w == needle.as_bytes())
        .expect("needle");
    let mut bad = bytes.clone();
    bad[at + needle.len() - 1] = b'7';
    let e = error(&bad, &Limits::default());
    assert!(e.contains("textures") || e.contains("index"), "{e}");
}

/// `rgba` (w x h) as PNG bytes.
fn png(w: u32, h: u32, rgba: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut out),
        rgba,
        w,
        h,
        image::ExtendedColorType::Rgba8,
    )
    .expect("png");
    out
}

#[test]
fn obj_maps_and_vt_are_read() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = dir.path();
    std::fs::write(
        p.join("c.png"),
        png(2, 1, &[255, 0, 0, 255, 0, 0, 255, 255]),
    )
    .expect("png");
    std::fs::write(p.join("n.png"), png(1, 1, &[200, 128, 230, 255])).expect("png");
    std::fs::write(p.join("h.png"), png(1, 1, &[90, 90, 90, 255])).expect("png");
    std::fs::write(p.join("junk.png"), b"not an image").expect("junk");
    let mtl =
        "newmtl painted\nKd 1 1 1\nmap_Kd -clamp on -o 0.5 0.25 -s 2 3 c.png\nnorm -bm 0.5 n.png\n\
               newmtl embossed\nKd 1 1 1\nbump h.png\n";
    std::fs::write(p.join("m.mtl"), mtl).expect("mtl");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
               usemtl painted\nf 1/1/1 2/2/1 3/3/1\nusemtl embossed\nf 1/1/1 3/3/1 2/2/1\n";
    std::fs::write(p.join("m.obj"), obj).expect("obj");
    let m = crate::model::load_file(&p.join("m.obj"), &Limits::default()).expect("loads");
    assert_eq!(m.images.len(), 3, "c, n and the height map");
    let (_, _, painted) = &m.materials[0];
    let b = painted.base_color.expect("map_Kd");
    assert_eq!(
        (b.wrap, b.offset, b.scale),
        ([Wrap::Clamp; 2], [0.5, 0.25], [2.0, 3.0])
    );
    assert_eq!(m.images[b.image].rgba, [255, 0, 0, 255, 0, 0, 255, 255]);
    let n = painted.normal.expect("norm");
    assert_eq!(
        (m.images[n.image].name.as_str(), painted.normal_scale),
        ("n.png", 0.5)
    );
    // The grey bump map is a height map: noted, not used.
    assert!(m.materials[1].2.normal.is_none());
    assert!(
        m.warnings
            .iter()
            .any(|w| w.contains("\"h.png\" is a height map")),
        "{:?}",
        m.warnings
    );
    // vt flipped to glTF's top-left origin; tangents for the normal map.
    let mesh = &m.meshes[0];
    let uvs = mesh.uvs[0].as_ref().expect("uvs");
    assert!(uvs.contains(&[0.0, 1.0]) && uvs.contains(&[1.0, 1.0]) && uvs.contains(&[0.0, 0.0]));
    assert!(mesh.tangents.is_some());
    // A map that is not an image is an error naming it.
    std::fs::write(p.join("m.mtl"), "newmtl painted\nmap_Kd junk.png\n").expect("mtl");
    let e = crate::model::load_file(&p.join("m.obj"), &Limits::default()).expect_err("junk");
    assert!(e.to_string().contains("junk.png"), "{e}");
}

#[test]
fn obj_map_ke_multiplies_ke_or_is_the_emission() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = dir.path();
    std::fs::write(p.join("e.png"), png(1, 1, &[255, 128, 0, 255])).expect("png");
    let mtl = "newmtl both\nKd 0 0 0\nKe 2 2 2\nmap_Ke -s 2 2 e.png\n\
               newmtl map\nKd 0 0 0\nmap_Ke e.png\n\
               newmtl lost\nKd 0 0 0\nmap_Ke missing.png\n";
    std::fs::write(p.join("m.mtl"), mtl).expect("mtl");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
               usemtl both\nf 1/1 2/2 3/3\nusemtl map\nf 1/1 3/3 2/2\nusemtl lost\nf 2/2 1/1 3/3\n";
    std::fs::write(p.join("m.obj"), obj).expect("obj");
    let m = crate::model::load_file(&p.join("m.obj"), &Limits::default()).expect("loads");
    let emission = |i: usize| match m.materials[i].1 {
        crate::model::Material::Diffuse { emission, .. } => emission,
        ref other => panic!("{other:?}"),
    };
    let both = m.materials[0].2.emission.expect("map_Ke");
    assert_eq!((emission(0), both.scale), (Some([2.0; 3]), [2.0, 2.0]));
    assert_eq!(m.images[both.image].rgba, [255, 128, 0, 255]);
    // No Ke: the map is the emission; a map that cannot be read, no glow.
    assert_eq!(emission(1), Some([1.0; 3]));
    assert!(m.materials[1].2.emission.is_some());
    assert_eq!((emission(2), m.materials[2].2.emission), (None, None));
    assert!(
        m.warnings.iter().any(|w| w.contains("missing.png")),
        "{:?}",
        m.warnings
    );
}

#[test]
fn obj_map_ks_is_a_pbr_specular_colour_texture() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = dir.path();
    std::fs::write(p.join("s.png"), png(1, 1, &[255, 64, 0, 255])).expect("png");
    let mtl = "newmtl shiny\nKd 1 1 1\nPr 0.3\nmap_Ks -clamp on -s 2 2 s.png\n\
               newmtl phong\nKd 1 1 1\nmap_Ks s.png\n";
    std::fs::write(p.join("m.mtl"), mtl).expect("mtl");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
               usemtl shiny\nf 1/1 2/2 3/3\nusemtl phong\nf 1/1 3/3 2/2\n";
    std::fs::write(p.join("m.obj"), obj).expect("obj");
    let m = crate::model::load_file(&p.join("m.obj"), &Limits::default()).expect("loads");
    let s = m.materials[0].2.specular_color.expect("map_Ks");
    assert_eq!((s.wrap, s.scale), ([Wrap::Clamp; 2], [2.0, 2.0]));
    assert_eq!(m.images[s.image].rgba, [255, 64, 0, 255]);
    // A diffuse material has no F0 to tint: noted, not read.
    assert!(m.materials[1].2.specular_color.is_none());
    assert!(
        m.warnings
            .iter()
            .any(|w| w.contains("\"phong\"") && w.contains("map_Ks")),
        "{:?}",
        m.warnings
    );
}
