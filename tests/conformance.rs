//! What the glTF spec says a viewer shows, on fixtures built here: vertex colours (`COLOR_0`
//! of every accessor type the spec allows, multiplied into the base color and its alpha) and
//! single-sided surfaces seen from behind (culled for camera rays), in both kernels.

mod common;

use common::{Gltf, Prim, render_exr};
use serde_json::json;
use std::path::{Path, PathBuf};

const SIZE: usize = 32;
const KERNELS: [&str; 2] = ["wavefront", "megakernel"];

/// Renders `scene` with `kernel` at SIZE² under a uniform sky of radiance 1 with no bounce
/// after the first hit: a Lambertian surface of albedo a facing the camera then has radiance
/// a exactly (every BSDF sample escapes to the sky), and the sky seen past it is 1.
fn render_under_unit_sky(scene: &Path, kernel: &str) -> Vec<[f32; 3]> {
    let size = SIZE.to_string();
    let out = scene.with_extension(format!("{kernel}.exr"));
    let (summary, px) = render_exr(
        scene,
        &out,
        &[
            "--kernel",
            kernel,
            "--width",
            &size,
            "--height",
            &size,
            "--spp",
            "4",
            "--bounces",
            "0",
            "--env",
            "1",
        ],
    );
    assert_eq!(summary["nonfinite_samples"], 0);
    px
}

/// The mean colour of the 6×6 pixels around the centre of quadrant (qx, qy) (0: left / top).
fn quadrant(px: &[[f32; 3]], qx: usize, qy: usize) -> [f64; 3] {
    let (cx, cy) = (qx * SIZE / 2 + SIZE / 4, qy * SIZE / 2 + SIZE / 4);
    let mut m = [0.0f64; 3];
    for y in cy - 3..cy + 3 {
        for x in cx - 3..cx + 3 {
            for c in 0..3 {
                m[c] += px[y * SIZE + x][c] as f64 / 36.0;
            }
        }
    }
    m
}

fn assert_color(what: &str, got: [f64; 3], want: [f64; 3]) {
    let close = got.iter().zip(&want).all(|(g, w)| (g - w).abs() < 2e-3);
    assert!(close, "{what}: {got:?}, expected {want:?}");
}

/// A camera on +Z looking at the origin, its view filled by the square |x|, |y| < 0.8.
fn add_camera(g: &mut Gltf, z: f32, turned: bool) {
    let yfov = 2.0 * (0.8f32 / z).atan();
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": yfov, "znear": 0.01}}));
    // Turned half a turn about Y, it looks from −Z at the squares' backs.
    let (translation, rotation) = if turned {
        ([0.0, 0.0, -z], [0.0, 1.0, 0.0, 0.0])
    } else {
        ([0.0, 0.0, z], [0.0, 0.0, 0.0, 1.0])
    };
    g.node(json!({"camera": 0, "translation": translation, "rotation": rotation}));
}

/// A unit square in the z = 0 plane facing +Z with its lower left corner at (x, y).
fn square(x: f32, y: f32, material: usize) -> Prim {
    Prim::triangles(
        vec![
            [x, y, 0.0],
            [x + 1.0, y, 0.0],
            [x + 1.0, y + 1.0, 0.0],
            [x, y + 1.0, 0.0],
        ],
        vec![0, 1, 2, 0, 2, 3],
        material,
    )
}

/// How a fixture stores `COLOR_0`.
#[derive(Clone, Copy, Debug)]
enum ColorAccessor {
    /// FLOAT.
    Float,
    /// UNSIGNED_BYTE, normalized.
    U8,
    /// UNSIGNED_SHORT, normalized.
    U16,
}

/// Adds a `COLOR_0` accessor of four vertices of colour `c` (RGB, or RGBA when `rgba`).
fn color_accessor(g: &mut Gltf, kind: ColorAccessor, c: [f32; 4], rgba: bool) -> usize {
    let n = if rgba { 4 } else { 3 };
    let values: Vec<f32> = (0..4).flat_map(|_| c[..n].to_vec()).collect();
    let (bytes, component): (Vec<u8>, u32) = match kind {
        ColorAccessor::Float => (values.iter().flat_map(|v| v.to_le_bytes()).collect(), 5126),
        ColorAccessor::U8 => (
            values.iter().map(|v| (v * 255.0).round() as u8).collect(),
            5121,
        ),
        ColorAccessor::U16 => (
            values
                .iter()
                .flat_map(|v| ((v * 65535.0).round() as u16).to_le_bytes())
                .collect(),
            5123,
        ),
    };
    // Each vertex's colour padded to four bytes, as the spec requires of vertex attributes.
    let element = bytes.len() / 4;
    let stride = element.next_multiple_of(4);
    let mut padded = vec![];
    for v in bytes.chunks(element) {
        padded.extend_from_slice(v);
        padded.resize(padded.len() + stride - element, 0);
    }
    let view = g.bytes_view(&padded);
    g.views[view]["byteStride"] = json!(stride);
    let mut accessor = json!({"bufferView": view, "componentType": component, "count": 4,
                              "type": if rgba { "VEC4" } else { "VEC3" }});
    if !matches!(kind, ColorAccessor::Float) {
        accessor["normalized"] = json!(true);
    }
    g.accessors.push(accessor);
    g.accessors.len() - 1
}

/// Four squares of base color 0.5 grey in a 2×2 board facing the camera, whose vertex colours
/// are red (top left), green (top right), blue (bottom left) and yellow (bottom right), stored
/// as `kind` with three or four components. The yellow one's material is alpha-masked
/// (cutoff 0.5) and, with four components, its vertex alpha is 0.
///
/// A viewer shows the red, green and blue squares at half their colour's brightness; the
/// yellow one half-bright yellow with RGB colours (alpha 1), and with RGBA colours not at all:
/// the sky shows through its corner.
fn vertex_color_board(dir: &Path, kind: ColorAccessor, rgba: bool) -> PathBuf {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    g.materials[1]["alphaMode"] = json!("MASK");
    g.materials[1]["alphaCutoff"] = json!(0.5);
    let colors = [
        ([-1.0, 0.0], [1.0, 0.0, 0.0, 1.0], 0),
        ([0.0, 0.0], [0.0, 1.0, 0.0, 1.0], 0),
        ([-1.0, -1.0], [0.0, 0.0, 1.0, 1.0], 0),
        ([0.0, -1.0], [1.0, 1.0, 0.0, 0.0], 1),
    ];
    let mut prims = vec![];
    let mut accessors = vec![];
    for ([x, y], c, material) in colors {
        prims.push(square(x, y, material));
        accessors.push(color_accessor(&mut g, kind, c, rgba));
    }
    let mesh = g.mesh(prims);
    for (i, a) in accessors.into_iter().enumerate() {
        g.meshes[mesh]["primitives"][i]["attributes"]["COLOR_0"] = json!(a);
    }
    g.node(json!({"mesh": mesh}));
    add_camera(&mut g, 3.0, false);
    g.write_glb(
        dir,
        &format!("board-{kind:?}-{}", if rgba { "rgba" } else { "rgb" }),
    )
}

#[test]
fn vertex_colors_of_every_accessor_type_tint_the_base_color_in_both_kernels() {
    let dir = tempfile::tempdir().unwrap();
    for kind in [ColorAccessor::Float, ColorAccessor::U8, ColorAccessor::U16] {
        for rgba in [false, true] {
            let scene = vertex_color_board(dir.path(), kind, rgba);
            for kernel in KERNELS {
                let px = render_under_unit_sky(&scene, kernel);
                let what = |q: &str| {
                    format!(
                        "{kind:?} {} {kernel}: {q}",
                        if rgba { "RGBA" } else { "RGB" }
                    )
                };
                assert_color(&what("red"), quadrant(&px, 0, 0), [0.5, 0.0, 0.0]);
                assert_color(&what("green"), quadrant(&px, 1, 0), [0.0, 0.5, 0.0]);
                assert_color(&what("blue"), quadrant(&px, 0, 1), [0.0, 0.0, 0.5]);
                // Alpha 0 cuts the yellow square out (the unit sky behind it); RGB is opaque.
                let yellow = if rgba { [1.0; 3] } else { [0.5, 0.5, 0.0] };
                assert_color(&what("yellow"), quadrant(&px, 1, 1), yellow);
            }
        }
    }
}

/// A square of white base colour whose corners are red, green, blue and white: a viewer shows
/// the colours blended across it, each pure at its own corner.
#[test]
fn vertex_colors_blend_across_a_triangle() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    g.lambert([1.0; 3], [0.0; 3], 1.0, false);
    let mut p = square(-1.0, -1.0, 0);
    p.positions.iter_mut().flatten().for_each(|c| *c *= 2.0);
    p.positions.iter_mut().for_each(|v| {
        v[0] += 1.0;
        v[1] += 1.0;
    });
    let mesh = g.mesh(vec![p]);
    // Corners: bottom left red, bottom right green, top right blue, top left white.
    let colors = g.float_accessor(&[
        [1.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0, 1.0],
        [1.0, 1.0, 1.0, 1.0],
    ]);
    g.meshes[mesh]["primitives"][0]["attributes"]["COLOR_0"] = json!(colors);
    g.node(json!({"mesh": mesh}));
    add_camera(&mut g, 3.0, false);
    let scene = g.write_glb(dir.path(), "blend");
    for kernel in KERNELS {
        let px = render_under_unit_sky(&scene, kernel);
        let at = |x: usize, y: usize| px[y * SIZE + x].map(|c| c as f64);
        // In the corner pixels their own vertex's colour weighs 0.78 (the view reaches 0.8 of
        // the way to the corners), the other two vertices of its triangle 0.11 each.
        let corners = [
            ((0, SIZE - 1), 0),
            ((SIZE - 1, SIZE - 1), 1),
            ((SIZE - 1, 0), 2),
        ];
        for ((x, y), c) in corners {
            let p = at(x, y);
            let others = (0..3).filter(|&k| k != c).map(|k| p[k]).fold(0.0, f64::max);
            assert!(p[c] > 0.7 && others < 0.25, "{kernel}: corner {c} is {p:?}");
        }
        let top_left = at(0, 0);
        assert!(
            top_left.iter().all(|&v| v > 0.7),
            "{kernel}: white corner {top_left:?}"
        );
        // The middle lies on the diagonal from red to blue: half of each, no green.
        let h = SIZE / 2;
        let mut middle = [0.0; 3];
        for (x, y) in [(h - 1, h - 1), (h, h - 1), (h - 1, h), (h, h)] {
            for (m, v) in middle.iter_mut().zip(at(x, y)) {
                *m += v / 4.0;
            }
        }
        // (Within 0.03: the four pixels reach a fortieth of the side into the other corners.)
        let want = [0.5, 0.0, 0.5];
        let close = middle.iter().zip(want).all(|(m, w)| (m - w).abs() < 0.03);
        assert!(close, "{kernel}: middle {middle:?}, expected {want:?}");
    }
}

/// Two squares side by side facing +Z, each 1 wide and 2 high: at x < 0 a single-sided one
/// (placed by a node mirrored in x, whose determinant keeps its front facing +Z, as glTF's
/// winding rule says), at x > 0 a double-sided one; camera `turned` looks at their backs.
///
/// A viewer shows both from the front; from behind only the double-sided one (on the image's
/// left, as it is seen from behind): the single-sided one is culled and the sky shows.
fn single_and_double_sided(dir: &Path, turned: bool) -> PathBuf {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    g.lambert([0.5; 3], [0.0; 3], 1.0, true);
    let single = g.mesh(vec![square(0.0, -1.0, 0), square(0.0, 0.0, 0)]);
    let double = g.mesh(vec![square(0.0, -1.0, 1), square(0.0, 0.0, 1)]);
    g.node(json!({"mesh": single, "scale": [-1.0, 1.0, 1.0]}));
    g.node(json!({"mesh": double}));
    add_camera(&mut g, 3.0, turned);
    g.write_glb(
        dir,
        if turned {
            "sides-behind"
        } else {
            "sides-front"
        },
    )
}

#[test]
fn single_sided_surfaces_seen_from_behind_are_culled_in_both_kernels() {
    let dir = tempfile::tempdir().unwrap();
    let front = single_and_double_sided(dir.path(), false);
    let behind = single_and_double_sided(dir.path(), true);
    for kernel in KERNELS {
        let px = render_under_unit_sky(&front, kernel);
        for (qx, qy) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let what = format!("{kernel}, front, quadrant ({qx}, {qy})");
            assert_color(&what, quadrant(&px, qx, qy), [0.5; 3]);
        }
        let px = render_under_unit_sky(&behind, kernel);
        for qy in [0, 1] {
            let what = format!("{kernel}, behind, double-sided ({qy})");
            assert_color(&what, quadrant(&px, 0, qy), [0.5; 3]);
            let what = format!("{kernel}, behind, single-sided culled ({qy})");
            assert_color(&what, quadrant(&px, 1, qy), [1.0; 3]);
        }
    }
}
