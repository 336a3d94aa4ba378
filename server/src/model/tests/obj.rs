//! OBJ + MTL.

use super::{assert_guarantees, cube, untextured, Gen};
use crate::model::Material;
use crate::model::{load_bytes, load_file, Instance, Limits, Model};
use std::fmt::Write as _;

/// The cube as OBJ: every vertex and normal written once per face corner,
/// faces as `v//vn` quads, one `usemtl` per run of faces.
fn cube_obj(g: &Gen, names: [&str; 2], mtllib: Option<&str>) -> String {
    let mut s = String::from("# generated cube\n");
    if let Some(lib) = mtllib {
        let _ = writeln!(s, "mtllib {lib}");
    }
    for p in &g.positions {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    for n in &g.normals {
        let _ = writeln!(s, "vn {} {} {}", n[0], n[1], n[2]);
    }
    let mut current = None;
    for (poly, m) in &g.faces {
        if current != Some(*m) {
            let _ = writeln!(s, "usemtl {}", names[*m as usize]);
            current = Some(*m);
        }
        s.push('f');
        for i in poly {
            let _ = write!(s, " {}//{}", i + 1, i + 1);
        }
        s.push('\n');
    }
    s
}

fn diffuse(albedo: [f64; 3], emission: Option<[f64; 3]>) -> Material {
    Material::Diffuse { albedo, emission }
}

fn mirror(albedo: [f64; 3]) -> Material {
    Material::Mirror {
        albedo,
        emission: None,
    }
}

fn glass(ior: f64, albedo: Option<[f64; 3]>) -> Material {
    Material::Glass {
        ior,
        albedo,
        attenuation: None,
        emission: None,
    }
}

/// Per triangle: its corners' positions and normals, and its material's name.
type Soup = Vec<([[f32; 3]; 3], Option<[[f32; 3]; 3]>, String)>;

fn soup(m: &Model) -> Soup {
    let mesh = &m.meshes[0];
    mesh.triangles
        .iter()
        .zip(&mesh.materials)
        .map(|(t, &mat)| {
            let p = t.map(|i| mesh.positions[i as usize]);
            let n = mesh.normals.as_ref().map(|n| t.map(|i| n[i as usize]));
            (p, n, m.materials[mat as usize].0.clone())
        })
        .collect()
}

#[test]
fn cube_with_two_mtl_files_loads_exactly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let g = cube();
    std::fs::write(dir.path().join("a.mtl"), "newmtl paint\nKd 0.8 0.2 0.1\n").expect("write");
    std::fs::write(
        dir.path().join("b.mtl"),
        "newmtl chrome\nillum 3\nKs 0.9 0.9 0.9\n",
    )
    .expect("write");
    let path = dir.path().join("cube.obj");
    std::fs::write(
        &path,
        cube_obj(&g, ["paint", "chrome"], Some("a.mtl b.mtl")),
    )
    .expect("write");
    let m = load_file(&path, &Limits::default()).expect("loads");
    assert_guarantees(&m);
    assert_eq!(
        m,
        Model {
            meshes: vec![g.mesh("cube", &[0, 1])],
            materials: untextured([
                ("paint", diffuse([0.8, 0.2, 0.1], None)),
                ("chrome", mirror([0.9; 3])),
            ]),
            images: Vec::new(),
            instances: vec![Instance {
                mesh: 0,
                transform: [
                    [1.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, 0.0]
                ],
            }],
            camera: None,
            warnings: vec![],
        }
    );
}

#[test]
fn shared_vertices_are_split_per_normal() {
    // 8 corners and 6 normals, each face `v//vn` of shared ones: single
    // index gives 24 vertices, and the triangles' corners are unchanged.
    let g = cube();
    let mut corners: Vec<[f32; 3]> = Vec::new();
    let mut text = String::new();
    let mut faces = String::new();
    for (f, (poly, _)) in g.faces.iter().enumerate() {
        let n = g.normals[poly[0] as usize];
        let _ = writeln!(text, "vn {} {} {}", n[0], n[1], n[2]);
        faces.push('f');
        for &i in poly {
            let p = g.positions[i as usize];
            let k = corners.iter().position(|c| *c == p).unwrap_or_else(|| {
                corners.push(p);
                corners.len() - 1
            });
            let _ = write!(faces, " {}//{}", k + 1, f + 1);
        }
        faces.push('\n');
    }
    assert_eq!(corners.len(), 8);
    for c in &corners {
        let _ = writeln!(text, "v {} {} {}", c[0], c[1], c[2]);
    }
    text.push_str(&faces);
    let m = load_bytes(text.as_bytes(), "shared.obj", &Limits::default()).expect("loads");
    assert_guarantees(&m);
    assert_eq!(m.meshes[0].positions.len(), 24);
    let expected = load_bytes(
        cube_obj(&g, ["default", "default"], None).as_bytes(),
        "c.obj",
        &Limits::default(),
    )
    .expect("loads");
    assert_eq!(soup(&m), soup(&expected));
    assert_eq!(soup(&m).len(), 12);
}

const RULES_MTL: &str = "\
newmtl red
Kd 0.8 0.1 0.1
Ke 0 0 0
Ks 0 0 0
Ns 10
illum 2
newmtl lamp
Kd 0 0 0
Ke 4 3.5 2
newmtl chrome
illum 3
Ks 0.9 0.9 0.9
Kd 0.1 0.1 0.1
newmtl polished
illum 3
Kd 0.5 0.6 0.7
Ns 200
newmtl water
illum 7
Ni 1.33
Kd 0 0 0
Tf 0.9 1 0.9
newmtl glass_no_ni
illum 4
newmtl glass_bad_ni
illum 6
Ni 0.5
newmtl hot
Kd 1.5 0.5 -0.25
Ke -1 2 2
newmtl textured
Kd 0.5 0.5 0.5
Ks 0.5 0.5 0.5
Ns 96
Ka 0.1 0.1 0.1
d 0.5
map_Kd -s 2 2 2 wood.png
bump wood_n.png
Pr 0.5
newmtl unused
Kd 1 1 1
map_Kd unused.png
";

#[test]
fn mtl_rules_map_every_material() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("rules.mtl"), RULES_MTL).expect("write");
    let mut obj = String::from("mtllib rules.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    for name in [
        "red",
        "lamp",
        "chrome",
        "polished",
        "water",
        "glass_no_ni",
        "glass_bad_ni",
        "hot",
        "textured",
        "nosuch",
    ] {
        let _ = writeln!(obj, "usemtl {name}\nf 1 2 3");
    }
    let path = dir.path().join("rules.obj");
    std::fs::write(&path, obj).expect("write");
    let m = load_file(&path, &Limits::default()).expect("loads");
    assert_guarantees(&m);
    let names: Vec<&str> = m.materials.iter().map(|(n, _, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "red",
            "lamp",
            "chrome",
            "polished",
            "water",
            "glass_no_ni",
            "glass_bad_ni",
            "hot",
            "textured",
            "default"
        ]
    );
    let json: Vec<&Material> = m.materials.iter().map(|(_, j, _)| j).collect();
    assert_eq!(
        json,
        [
            &diffuse([0.8, 0.1, 0.1], None),
            &diffuse([0.0; 3], Some([4.0, 3.5, 2.0])),
            &mirror([0.9; 3]),
            &mirror([0.5, 0.6, 0.7]),
            &glass(1.33, Some([0.9, 1.0, 0.9])),
            &glass(1.5, None),
            &glass(1.5, None),
            &diffuse([1.0, 0.5, 0.0], Some([0.0, 2.0, 2.0])),
            &Material::Pbr {
                base_color: [0.5; 3],
                metallic: 0.0,
                roughness: 0.5,
                ior: 1.5,
                transmission: 0.0,
                thin: false,
                attenuation: None,
                clearcoat: 0.0,
                clearcoat_roughness: 0.0,
                specular: 1.0,
                specular_color: [1.0; 3],
                emission: None,
            },
            &diffuse([0.8; 3], None),
        ]
    );
    let mesh = &m.meshes[0];
    assert_eq!(mesh.materials, vec![9, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9]);
    assert_eq!(mesh.positions.len(), 33);
    assert!(mesh
        .positions
        .chunks(3)
        .all(|c| c == [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]));
    assert_eq!(
        mesh.triangles,
        (0..11)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect::<Vec<_>>()
    );
    assert_eq!(
        m.warnings,
        [
            "usemtl \"nosuch\": no material of that name was loaded: default material",
            "2 triangles have no material: default diffuse (albedo 0.8)",
            "map_Kd \"wood.png\": cannot be read (No such file or directory (os error 2)): not rendered",
            "bump map \"wood_n.png\": cannot be read (No such file or directory (os error 2)): not rendered",
            "material \"polished\": not modelled, ignored: Ns (the mirror is perfect)",
            "material \"glass_no_ni\": no Ni: ior 1.5",
            "material \"glass_bad_ni\": Ni 0.5 is not an index of refraction in [1, 10]: ior 1.5",
            "material \"hot\": Ke [-1, 2, 2] is negative or not finite: those components are 0",
            "material \"hot\": Kd [1.5, 0.5, -0.25] is outside [0, 1]: clamped to [1, 0.5, 0]",
            "material \"textured\": not modelled, ignored: Ka (ambient), Ks/Ns (Pr and Pm describe the highlight)",
        ]
    );
    // d 0.5: seen through half the time.
    let textured = &m.materials[8].2;
    assert_eq!(
        (textured.alpha_mode, textured.alpha),
        (crate::model::AlphaMode::Blend, 0.5)
    );
    assert_eq!(m.materials[0].2.alpha_mode, crate::model::AlphaMode::Opaque);
}

#[test]
fn mtl_pbr_keys_make_the_metallic_roughness_model() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mtl = "newmtl brushed\nKd 0.9 0.6 0.3\nPm 1\nPr 1.5\nNi 1.45\nPc 0.2\n\
               newmtl mirror_wins\nillum 3\nKd 0.5 0.5 0.5\nPr 0.1\n";
    std::fs::write(dir.path().join("pbr.mtl"), mtl).expect("write");
    let obj = "mtllib pbr.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl brushed\nf 1 2 3\nusemtl mirror_wins\nf 1 2 3\n";
    let path = dir.path().join("pbr.obj");
    std::fs::write(&path, obj).expect("write");
    let m = load_file(&path, &Limits::default()).expect("loads");
    assert_guarantees(&m);
    assert_eq!(
        m.materials,
        untextured([
            (
                "brushed",
                Material::Pbr {
                    base_color: [0.9, 0.6, 0.3],
                    metallic: 1.0,
                    roughness: 1.0,
                    ior: 1.45,
                    transmission: 0.0,
                    thin: false,
                    attenuation: None,
                    clearcoat: 0.0,
                    clearcoat_roughness: 0.0,
                    specular: 1.0,
                    specular_color: [1.0; 3],
                    emission: None,
                }
            ),
            ("mirror_wins", mirror([0.5; 3])),
        ])
    );
    assert_eq!(
        m.warnings,
        [
            "material \"brushed\": Pr 1.5 is outside [0, 1]: clamped to 1",
            "material \"brushed\": not modelled, ignored: Pc",
            "material \"mirror_wins\": not modelled, ignored: Pr/Pm (illum says mirror or glass)",
        ]
    );
}

#[test]
fn uploads_cannot_follow_mtllib() {
    let g = cube();
    let text = cube_obj(&g, ["paint", "chrome"], Some("a.mtl b.mtl"));
    let m = load_bytes(text.as_bytes(), "cube.obj", &Limits::default()).expect("loads");
    assert_guarantees(&m);
    assert_eq!(m.meshes, vec![g.mesh("cube", &[0, 0])]);
    assert_eq!(
        m.materials,
        untextured([("default", diffuse([0.8; 3], None))])
    );
    assert_eq!(
        m.warnings,
        [
            "mtllib \"a.mtl b.mtl\": an upload cannot refer to other files: its materials fall back to the default",
            "usemtl \"paint\": no material of that name was loaded: default material",
            "usemtl \"chrome\": no material of that name was loaded: default material",
            "12 triangles have no material: default diffuse (albedo 0.8)",
        ]
    );
}

#[test]
fn mtl_problems() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("t.obj");
    std::fs::write(
        &path,
        "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    )
    .expect("write");
    std::fs::write(dir.path().join("bad.mtl"), "newmtl a\nKd 1 x 1\n").expect("write");
    let e = load_file(&path, &Limits::default()).expect_err("bad mtl");
    assert_eq!(
        e.to_string(),
        format!(
            "{}: bad.mtl: line 2: Kd: \"x\" is not a number",
            path.display()
        )
    );

    std::fs::write(dir.path().join("bad.mtl"), "newmtl a\nKd 0.5\n").expect("write");
    let m = load_file(&path, &Limits::default()).expect("Kd with one number");
    assert_eq!(m.materials, untextured([("a", diffuse([0.5; 3], None))]));

    std::fs::remove_file(dir.path().join("bad.mtl")).expect("rm");
    let m = load_file(&path, &Limits::default()).expect("loads without the mtl");
    assert!(
        m.warnings[0].starts_with("mtllib \"bad.mtl\": cannot be read ("),
        "{:?}",
        m.warnings
    );
    assert!(m.warnings[0].ends_with("): its materials fall back to the default"));
}

#[test]
fn normals_and_colours() {
    let tri = "v 0 0 0 1 0 0\nv 1 0 0 1 0 0\nv 0 1 0 1 0 0\nv 0 0 1 1 0 0\n";
    // Normals on one face only: dropped. Vertex colours: a warning.
    let text = format!("{tri}vn 0 0 2\nf 1//1 2//1 3//1\ng other\nf 1 2 4\n");
    let m = load_bytes(text.as_bytes(), "n.obj", &Limits::default()).expect("loads");
    assert_guarantees(&m);
    assert_eq!(m.meshes[0].normals, None);
    assert_eq!(
        m.warnings,
        [
            "vertex colours ignored",
            "2 triangles have no material: default diffuse (albedo 0.8)",
            "mesh \"n\": some faces have no vn normals: normals dropped (flat shading)",
        ]
    );
    // A normal of length 2 is normalised; a zero normal drops them all.
    let m = load_bytes(
        format!("{tri}vn 0 0 2\nf 1//1 2//1 3//1\n").as_bytes(),
        "n.obj",
        &Limits::default(),
    )
    .expect("loads");
    assert_eq!(m.meshes[0].normals, Some(vec![[0.0, 0.0, 1.0]; 3]));
    let m = load_bytes(
        format!("{tri}vn 0 0 0\nf 1//1 2//1 3//1\n").as_bytes(),
        "z.obj",
        &Limits::default(),
    )
    .expect("loads");
    assert_eq!(m.meshes[0].normals, None);
    assert!(m.warnings.contains(
        &"mesh \"z\": the normal of vertex 0 is [0, 0, 0] (zero or not finite): the mesh's normals are dropped (flat shading)"
            .to_owned()
    ));
}

#[test]
fn degenerate_triangles_are_kept_and_counted() {
    let text = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\nf 1 1 4\n";
    let m = load_bytes(text.as_bytes(), "d.obj", &Limits::default()).expect("loads");
    assert_eq!(m.meshes[0].triangles.len(), 3);
    assert!(m
        .warnings
        .contains(&"mesh \"d\": 2 of 3 triangles have zero area (kept)".to_owned()));
}
