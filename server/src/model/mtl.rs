//! MTL material libraries (read here rather than by `tobj`, which panics on
//! `Kd 0.5` and reports no line numbers), and their mapping to scene
//! materials:
//!
//! - `Kd` -> diffuse albedo (0.8 when missing, with a note); `Ke` -> emission;
//! - `d` (dissolve; else 1 - `Tr`) below 1 -> stochastic transparency with
//!   that opacity (glTF's alpha mode BLEND: meshes are seen through);
//! - `illum 3` -> mirror, albedo `Ks` if nonzero, else `Kd`;
//! - `illum 4` to `7` -> glass, ior `Ni` (1.5 with a note when missing or
//!   outside [1, 10]), albedo `Tf` when given (else clear);
//! - otherwise, with the PBR extension's `Pr` (roughness) or `Pm`
//!   (metallic): glTF's metallic-roughness model (`pbr`), base colour `Kd`,
//!   roughness `Pr` (default 1), metallic `Pm` (default 0), ior `Ni` (1.5
//!   when missing), each clamped to its range with a note;
//! - `illum 0` to `2` (or none) -> diffuse; other `illum` values -> diffuse
//!   with a note;
//! - `map_Kd` -> a base colour texture (`-clamp on` clamps, else it
//!   repeats; `-o` and `-s` offset and scale its coordinates); `map_Ke` ->
//!   an emission texture (the same options; it multiplies `Ke`, 1 where
//!   `Ke` is missing); `map_Ks` -> a `pbr` material's specular colour
//!   texture (`KHR_materials_specular`'s, which tints the dielectric's F0:
//!   white keeps it; `Ks` itself stays unread, the options as `map_Kd`;
//!   noted on other kinds); `norm`, `map_Bump` or `bump` -> a normal map (`-bm` its
//!   scale) when the image is one, a height map (grey) is noted as not
//!   rendered; both need `vt` coordinates (v flipped to glTF's top-left
//!   origin);
//! - whatever else changes the look (other textures `map_*`, `disp`,
//!   `decal`, `refl`; `Ks`/`Ns` of non-mirrors; `Ka`; `Tf` of non-glass; the PBR keys other than `Pr` and `Pm`
//!   and unknown statements) is listed in one note per material.

use super::common::{self, Mat};
use super::Material;

/// A colour texture's file, whether `-clamp on` was given, and its `-o`
/// offset and `-s` scale (u and v).
pub(super) type ColorMap = (String, bool, [f64; 2], [f64; 2]);

/// One `newmtl` block, as written.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct MtlMaterial {
    pub name: String,
    pub kd: Option<[f64; 3]>,
    pub ks: Option<[f64; 3]>,
    pub ke: Option<[f64; 3]>,
    pub ka: Option<[f64; 3]>,
    pub tf: Option<[f64; 3]>,
    pub ns: Option<f64>,
    pub ni: Option<f64>,
    pub d: Option<f64>,
    pub tr: Option<f64>,
    /// The PBR extension's roughness and metallic.
    pub pr: Option<f64>,
    pub pm: Option<f64>,
    pub illum: Option<i64>,
    /// `map_Kd`'s file, whether `-clamp on` was given, and its `-o` offset
    /// and `-s` scale (u and v).
    pub map_kd: Option<ColorMap>,
    /// `map_Ke` and `map_Ks`, as `map_Kd`.
    pub map_ke: Option<ColorMap>,
    pub map_ks: Option<ColorMap>,
    /// `norm`, `map_Bump` or `bump`'s file and its `-bm` scale (a normal
    /// map, or a height map that the loader then notes as not rendered).
    pub bump: Option<(String, f64)>,
    /// Statements not modelled, as keywords (`map_Kd`, `Kd spectral`, ...).
    pub ignored: Vec<String>,
}

/// An error in an MTL file: its 1-based line and what is wrong.
#[derive(Debug, PartialEq)]
pub(super) struct MtlError {
    pub line: usize,
    pub reason: String,
}

/// Reads an MTL file's text. Statements before the first `newmtl` are
/// skipped; an unreadable number is an error.
pub(super) fn parse(text: &str) -> Result<Vec<MtlMaterial>, MtlError> {
    let mut out: Vec<MtlMaterial> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let stmt = raw.split('#').next().unwrap_or_default().trim();
        let mut words = stmt.split_whitespace();
        let Some(key) = words.next() else { continue };
        let err = |reason: String| MtlError { line, reason };
        if key == "newmtl" {
            let name = stmt[key.len()..].trim();
            if name.is_empty() {
                return Err(err("newmtl without a name".to_owned()));
            }
            out.push(MtlMaterial {
                name: name.to_owned(),
                ..Default::default()
            });
            continue;
        }
        let Some(m) = out.last_mut() else { continue };
        let args: Vec<&str> = words.collect();
        let lower = key.to_ascii_lowercase();
        match lower.as_str() {
            "kd" | "ks" | "ke" | "ka" | "tf" => {
                let Some(c) = color(key, &args).map_err(err)? else {
                    m.ignored.push(format!(
                        "{key} {}",
                        args.first().copied().unwrap_or_default()
                    ));
                    continue;
                };
                let slot = match lower.as_str() {
                    "kd" => &mut m.kd,
                    "ks" => &mut m.ks,
                    "ke" => &mut m.ke,
                    "ka" => &mut m.ka,
                    _ => &mut m.tf,
                };
                *slot = Some(c);
            }
            "ns" | "ni" | "d" | "tr" | "pr" | "pm" => {
                let v = number(key, args.last().copied()).map_err(err)?;
                let slot = match lower.as_str() {
                    "ns" => &mut m.ns,
                    "ni" => &mut m.ni,
                    "d" => &mut m.d,
                    "pr" => &mut m.pr,
                    "pm" => &mut m.pm,
                    _ => &mut m.tr,
                };
                *slot = Some(v);
            }
            "illum" => {
                let word = args.first().copied().unwrap_or_default();
                m.illum = Some(
                    word.parse()
                        .map_err(|_| err(format!("illum: {word:?} is not an integer")))?,
                );
            }
            "map_kd" | "map_ke" | "map_ks" | "norm" | "map_bump" | "bump" => {
                let Some((&file, options)) = args.split_last() else {
                    return Err(err(format!("{key}: a file name is missing")));
                };
                let option = |name: &str| {
                    let i = options.iter().position(|o| o.eq_ignore_ascii_case(name))?;
                    options.get(i + 1).copied()
                };
                if lower.starts_with("map_k") {
                    let pair = |name: &str, default: f64| -> Result<[f64; 2], MtlError> {
                        let Some(i) = options.iter().position(|o| o.eq_ignore_ascii_case(name))
                        else {
                            return Ok([default; 2]);
                        };
                        let u = number(key, options.get(i + 1).copied()).map_err(err)?;
                        let v = match options.get(i + 2).map(|w| w.parse::<f64>()) {
                            Some(Ok(v)) => v,
                            _ => default,
                        };
                        Ok([u, v])
                    };
                    let (offset, scale) = (pair("-o", 0.0)?, pair("-s", 1.0)?);
                    let clamp = option("-clamp") == Some("on");
                    let map = Some((file.to_owned(), clamp, offset, scale));
                    match lower.as_str() {
                        "map_kd" => m.map_kd = map,
                        "map_ks" => m.map_ks = map,
                        _ => m.map_ke = map,
                    }
                } else {
                    let scale = match option("-bm") {
                        Some(w) => number(key, Some(w)).map_err(err)?,
                        None => 1.0,
                    };
                    m.bump = Some((file.to_owned(), scale));
                }
            }
            _ => m.ignored.push(key.to_owned()),
        }
    }
    Ok(out)
}

fn number(key: &str, word: Option<&str>) -> Result<f64, String> {
    let word = word.ok_or_else(|| format!("{key}: a number is missing"))?;
    word.parse()
        .map_err(|_| format!("{key}: {word:?} is not a number"))
}

/// `K r [g b]` (g and b default to r); `None` for the `spectral` and `xyz`
/// forms, which are not read.
fn color(key: &str, args: &[&str]) -> Result<Option<[f64; 3]>, String> {
    match args {
        [] => Err(format!("{key}: a colour is missing")),
        [form, ..] if matches!(*form, "spectral" | "xyz") => Ok(None),
        [r] => {
            let r = number(key, Some(r))?;
            Ok(Some([r; 3]))
        }
        [r, g, b, ..] => Ok(Some([
            number(key, Some(r))?,
            number(key, Some(g))?,
            number(key, Some(b))?,
        ])),
        _ => Err(format!(
            "{key}: expected one or three numbers, got {}",
            args.len()
        )),
    }
}

fn nonzero(c: Option<[f64; 3]>) -> bool {
    c.is_some_and(|c| c.iter().any(|&x| x != 0.0))
}

/// The scene material for an MTL material, following the rules of the
/// module doc; what is not modelled goes into the material's notes.
pub(super) fn to_material(m: &MtlMaterial) -> Mat {
    let mut notes = Vec::new();
    let mut ignored = m.ignored.clone();
    let illum = m.illum.unwrap_or(if nonzero(m.ks) { 2 } else { 1 });
    let mirror = illum == 3;
    let glass = (4..=7).contains(&illum);
    let pbr = !mirror && !glass && (m.pr.is_some() || m.pm.is_some());
    // An emission map without `Ke` is the emission itself.
    let ke = match (m.ke, &m.map_ke) {
        (None, Some(_)) => [1.0; 3],
        (ke, _) => ke.unwrap_or_default(),
    };
    let emission = common::emission("Ke", ke, &mut notes);

    if nonzero(m.ka) {
        ignored.push("Ka (ambient)".to_owned());
    }
    // Dissolve: `d`, else 1 - `Tr`; below 1, stochastic transparency.
    let opacity = match (m.d, m.tr) {
        (Some(d), _) => d,
        (None, Some(tr)) => 1.0 - tr,
        (None, None) => 1.0,
    };
    let mut maps = super::Maps::default();
    if opacity.is_finite() && opacity < 1.0 {
        maps.alpha_mode = super::AlphaMode::Blend;
        maps.alpha = opacity.max(0.0);
    }
    if !pbr && !(0..=7).contains(&illum) {
        ignored.push(format!("illum {illum} (rendered diffuse)"));
    }
    if !pbr && m.map_ks.is_some() {
        ignored.push("map_Ks (a specular colour texture needs Pr or Pm)".to_owned());
    }
    if !mirror && !glass && nonzero(m.ks) {
        ignored.push(match pbr {
            true => "Ks/Ns (Pr and Pm describe the highlight)".to_owned(),
            false => "Ks/Ns (specular highlight)".to_owned(),
        });
    }
    if (mirror || glass) && (m.pr.is_some() || m.pm.is_some()) {
        ignored.push("Pr/Pm (illum says mirror or glass)".to_owned());
    }
    if mirror && m.ns.is_some() {
        ignored.push("Ns (the mirror is perfect)".to_owned());
    }
    if !glass && m.tf.is_some() {
        ignored.push("Tf (only glass transmits)".to_owned());
    }
    if glass && nonzero(m.kd) {
        ignored.push("Kd (glass is tinted by Tf)".to_owned());
    }

    let kd = || match m.kd {
        Some(kd) => kd,
        None => [common::DEFAULT_ALBEDO; 3],
    };
    let json = if glass {
        let ior = common::ior("Ni", m.ni, &mut notes);
        let albedo = m.tf.map(|tf| common::albedo("Tf", tf, &mut notes));
        Material::Glass {
            ior,
            albedo,
            attenuation: None,
            emission,
        }
    } else if mirror {
        let (what, c) = if nonzero(m.ks) {
            ("Ks", m.ks.unwrap_or_default())
        } else {
            ("Kd", kd())
        };
        Material::Mirror {
            albedo: common::albedo(what, c, &mut notes),
            emission,
        }
    } else if pbr {
        if m.kd.is_none() {
            notes.push(format!("no Kd: base colour {}", common::DEFAULT_ALBEDO));
        }
        Material::Pbr {
            base_color: common::albedo("Kd", kd(), &mut notes),
            metallic: common::unit("Pm", m.pm.unwrap_or(0.0), &mut notes),
            roughness: common::unit("Pr", m.pr.unwrap_or(1.0), &mut notes),
            ior: match m.ni {
                Some(ni) => common::ior("Ni", Some(ni), &mut notes),
                None => common::DEFAULT_IOR,
            },
            transmission: 0.0,
            thin: false,
            attenuation: None,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            specular: 1.0,
            specular_color: [1.0; 3],
            emission,
        }
    } else {
        if m.kd.is_none() {
            notes.push(format!("no Kd: albedo {}", common::DEFAULT_ALBEDO));
        }
        Material::Diffuse {
            albedo: common::albedo("Kd", kd(), &mut notes),
            emission,
        }
    };
    if !ignored.is_empty() {
        notes.push(format!("not modelled, ignored: {}", ignored.join(", ")));
    }
    Mat {
        name: m.name.clone(),
        json,
        maps,
        notes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_statements_and_reports_lines() {
        let text = "# lib\nKd 1 1 1\nnewmtl a b\n  Kd 0.5\nKs 0.1 0.2 0.3 # trailing\nNi 1.4\nillum 7\nmap_Kd -s 1 1 1 t.png\nKa spectral x.rfl\n";
        let mats = parse(text).expect("parses");
        assert_eq!(
            mats,
            vec![MtlMaterial {
                name: "a b".into(),
                kd: Some([0.5; 3]),
                ks: Some([0.1, 0.2, 0.3]),
                ni: Some(1.4),
                illum: Some(7),
                map_kd: Some(("t.png".into(), false, [0.0; 2], [1.0; 2])),
                ignored: vec!["Ka spectral".into()],
                ..Default::default()
            }]
        );
        assert_eq!(
            parse("newmtl a\nKd 1 x 1\n"),
            Err(MtlError {
                line: 2,
                reason: "Kd: \"x\" is not a number".into()
            })
        );
        assert_eq!(
            parse("newmtl a\nKd 1 1\n").map_err(|e| e.reason),
            Err("Kd: expected one or three numbers, got 2".into())
        );
        assert_eq!(parse("newmtl a\nillum x\n").map_err(|e| e.line), Err(2));
        assert_eq!(
            parse("newmtl\n").map_err(|e| e.reason),
            Err("newmtl without a name".into())
        );
    }
}
