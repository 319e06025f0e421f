//! `COLOR_0`: a primitive's vertex colours as linear RGBA, from every accessor the glTF spec
//! allows for it (float, normalized unsigned byte or short; VEC3 or VEC4), and kept aligned
//! with the mesh's vertices when only some of its primitives have them.

use super::super::accessor::Attributes;
use glam::Vec4;
use gltf::json::accessor::Type;
use gltf::json::validation::Checked;

/// The primitive's `COLOR_0` (alpha 1 for VEC3), empty when it has none. The accessor's type
/// decides the width: a Draco primitive's decoded values come four to a point whatever the
/// accessor says, unused lanes zero, so an RGB colour's alpha lane is set to 1 here.
pub(super) fn read_colors(attributes: &Attributes, vertices: usize) -> Result<Vec<Vec4>, String> {
    let Some(&index) = attributes.accessors.get("COLOR_0") else {
        return Ok(Vec::new());
    };
    let rgb = matches!(
        attributes.root.accessors.get(index).map(|a| a.type_),
        Some(Checked::Valid(Type::Vec3))
    );
    let colors: Vec<Vec4> = if rgb {
        let rgb = attributes.floats::<3>("COLOR_0")?.unwrap_or_default();
        rgb.into_iter()
            .map(|c| Vec4::new(c[0], c[1], c[2], 1.0))
            .collect()
    } else {
        let rgba = attributes.floats::<4>("COLOR_0")?.unwrap_or_default();
        rgba.into_iter().map(Vec4::from).collect()
    };
    if colors.len() != vertices {
        return Err(format!(
            "{}: COLOR_0 count differs from POSITION count",
            attributes.path
        ));
    }
    // The spec's range is [0, 1]; outside it (or not finite) a colour would scale a
    // material's energy up or make it negative.
    Ok(colors
        .into_iter()
        .map(|c| {
            if c.is_finite() {
                c.clamp(Vec4::ZERO, Vec4::ONE)
            } else {
                Vec4::ONE
            }
        })
        .collect())
}

/// Appends a primitive's colours (`new`, for `new_len` vertices; empty when it has none) to
/// the mesh's (`dst`, `old_len` vertices so far), white where either side lacks them, so that
/// `dst` stays empty only while no primitive has colours.
pub(super) fn pad_colors(dst: &mut Vec<Vec4>, old_len: usize, new: Vec<Vec4>, new_len: usize) {
    if dst.is_empty() && new.is_empty() {
        return;
    }
    dst.resize(old_len, Vec4::ONE);
    if new.is_empty() {
        dst.extend(std::iter::repeat_n(Vec4::ONE, new_len));
    } else {
        dst.extend(new);
    }
}
