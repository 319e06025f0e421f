//! What the glTF specification calls invalid but penumbra can read anyway: each such value is
//! one warning naming the element (the docs promise it), and the scene still loads. Checked on
//! the validated document before anything reads it; the importer then uses the values as
//! documented in docs/robustness.md (a camera's clip planes and a light's range are not used).
//! Broken animation channels are reported where the clips are read (`animation::read_clips`).

use gltf::json;

/// Appends a warning for each value of `root` that the specification forbids and penumbra
/// tolerates. `glb_lengths`: a GLB file's header length and its real length.
pub fn warn_invalid(
    root: &json::Root,
    glb_lengths: Option<(u64, u64)>,
    warnings: &mut Vec<String>,
) {
    let mut warn = |w: String| warnings.push(w);
    if let Some((header, file)) = glb_lengths
        && header < file
    {
        warn(format!(
            "the GLB header's length {header} is shorter than the file ({file} bytes); the \
             bytes past it are ignored"
        ));
    }
    asset(&root.asset, &mut warn);
    for (m, mesh) in root.meshes.iter().enumerate() {
        if mesh.primitives.is_empty() {
            warn(format!(
                "meshes[{m}]: no primitives (at least one is required); nothing is drawn"
            ));
        }
        if let Some(w) = &mesh.weights {
            weights(&format!("meshes[{m}].weights"), w, targets(mesh), &mut warn);
        }
    }
    for (c, camera) in root.cameras.iter().enumerate() {
        camera_planes(c, camera, &mut warn);
    }
    if let Some(lights) = root
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
    {
        for (l, light) in lights.lights.iter().enumerate() {
            if let Some(range) = light.range
                && !greater(range, 0.0)
            {
                warn(format!(
                    "extensions.KHR_lights_punctual.lights[{l}].range: {range} is not positive; \
                     the light is not limited by a range"
                ));
            }
        }
    }
    for (n, node) in root.nodes.iter().enumerate() {
        node_transform(n, node, &mut warn);
        if let Some(w) = &node.weights {
            let mesh = node.mesh.and_then(|m| root.meshes.get(m.value()));
            weights(
                &format!("nodes[{n}].weights"),
                w,
                mesh.and_then(targets),
                &mut warn,
            );
        }
    }
}

/// `a > b`, false where either is NaN (NaN is never valid here).
fn greater(a: f32, b: f32) -> bool {
    a > b
}

/// `asset.version` must be 2.x and `minVersion` at most the 2.0 penumbra reads.
fn asset(asset: &json::Asset, warn: &mut impl FnMut(String)) {
    let major_minor = |v: &str| {
        let (major, minor) = v.split_once('.')?;
        Some((major.parse::<u64>().ok()?, minor.parse::<u64>().ok()?))
    };
    if !matches!(major_minor(&asset.version), Some((2, _))) {
        warn(format!(
            "asset.version: {:?} is not a glTF 2.x version; read as glTF 2.0",
            asset.version
        ));
    }
    if let Some(min) = &asset.min_version
        && major_minor(min).is_none_or(|v| v > (2, 0))
    {
        warn(format!(
            "asset.minVersion: {min:?} is newer than the glTF 2.0 penumbra reads; read as 2.0"
        ));
    }
}

/// The number of morph targets of `mesh`'s first primitive (the spec requires every
/// primitive to have as many), `None` for a mesh of no primitives.
fn targets(mesh: &json::Mesh) -> Option<usize> {
    let first = mesh.primitives.first()?;
    Some(first.targets.as_ref().map_or(0, Vec::len))
}

/// Morph target weights must be finite numbers, one for each of the mesh's morph targets.
fn weights(at: &str, weights: &[f32], targets: Option<usize>, warn: &mut impl FnMut(String)) {
    if let Some(bad) = weights.iter().find(|w| !w.is_finite()) {
        warn(format!("{at}: {bad} is not a finite weight; 0 is used"));
    }
    if let Some(n) = targets
        && weights.len() != n
    {
        warn(format!(
            "{at}: {} weights for {n} morph targets (the counts must match); a missing weight \
             is 0, an extra one is unused",
            weights.len()
        ));
    }
}

/// A camera's clip planes and aspect ratio: znear > 0, zfar > znear, aspectRatio > 0. They
/// are not used (penumbra traces rays without clipping and keeps the image's aspect).
fn camera_planes(c: usize, camera: &json::Camera, warn: &mut impl FnMut(String)) {
    let at = format!("cameras[{c}]");
    let mut problems = Vec::new();
    if let Some(p) = &camera.perspective {
        if !greater(p.znear, 0.0) {
            problems.push(format!("perspective.znear {} is not positive", p.znear));
        }
        if let Some(zfar) = p.zfar
            && !greater(zfar, p.znear)
        {
            problems.push(format!("perspective.zfar {zfar} is not beyond znear"));
        }
        if let Some(aspect) = p.aspect_ratio
            && !greater(aspect, 0.0)
        {
            problems.push(format!("perspective.aspectRatio {aspect} is not positive"));
        }
    }
    if let Some(o) = &camera.orthographic
        && (o.znear.is_nan() || o.znear < 0.0 || !greater(o.zfar, o.znear))
    {
        problems.push(format!(
            "orthographic.znear {} / zfar {} are not 0 ≤ znear < zfar",
            o.znear, o.zfar
        ));
    }
    if !problems.is_empty() {
        warn(format!("{at}: {}; ignored", problems.join(", ")));
    }
}

/// A node's `matrix` must not come with `translation`/`rotation`/`scale`, and must be affine
/// (last row 0, 0, 0, 1).
fn node_transform(n: usize, node: &json::Node, warn: &mut impl FnMut(String)) {
    let Some(m) = node.matrix else {
        return;
    };
    if node.translation.is_some() || node.rotation.is_some() || node.scale.is_some() {
        warn(format!(
            "nodes[{n}]: has both matrix and translation/rotation/scale; the matrix is used"
        ));
    }
    // Column-major: the last row is elements 3, 7, 11 and 15.
    if [m[3], m[7], m[11], m[15]] != [0.0, 0.0, 0.0, 1.0] {
        warn(format!(
            "nodes[{n}].matrix: its last row {:?} is not 0, 0, 0, 1 (a projective matrix); it \
             is read as affine",
            [m[3], m[7], m[11], m[15]]
        ));
    }
}
