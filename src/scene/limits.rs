//! Resource limits of the glTF import, in one place: whatever a file claims, loading it never
//! allocates more than these allow. Each limit is documented in docs/robustness.md; a file past one
//! fails with an error naming the element.

/// The most nodes the walk of the node graph visits, counting a node once for every path from
/// a scene root to it (a node listed as a child twice is placed twice). Bounds the number of
/// mesh instances, cameras and lights, and stops graphs that list children repeatedly at every
/// level from multiplying without end.
pub const MAX_NODE_INSTANCES: usize = 200_000;

/// The most triangles over all placed mesh instances (after instancing): 67 M, room for issue
/// 14's 64 M-triangle scenes. Loading and building keep about 110 bytes a unique triangle on
/// the host, about 7.5 GB at the limit.
pub const MAX_TRIANGLES: usize = 1 << 26;

/// The farthest a placed vertex may lie from the origin along any axis, in scene units. Past
/// it, f32 sums of squared distances (bounds, light falloff) overflow; the object is skipped
/// with a warning.
pub const MAX_COORDINATE: f64 = 1e15;

/// The deepest node nesting accepted (deeper graphs are most likely cycles).
pub const MAX_NODE_DEPTH: usize = 256;

/// The most elements an accessor may have when no buffer view bounds it (a sparse accessor
/// over zeros); accessors with a buffer view are bounded by the view's bytes.
pub const MAX_UNBACKED_ACCESSOR_COUNT: u64 = 1 << 24;

/// The largest side of a texture image, checked from the image header before decoding.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The most pixels of a texture image (8192 × 8192), checked before decoding.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 26;

/// The most bytes a texture decoder may allocate (a 16-bit RGBA image of
/// [`MAX_IMAGE_PIXELS`] plus its conversion).
pub const MAX_IMAGE_DECODE_BYTES: u64 = 1 << 30;

/// The most pixels all texture images of a scene may decode to together (2²⁹: 2 GiB as the
/// RGBA8 the scene keeps, e.g. 32 images of 4096²); images past it are left out with a
/// warning each. Which ones, when several are decoded at once, may differ between runs.
pub const MAX_DECODED_PIXELS: u64 = 1 << 29;

/// The largest side of an environment image (.hdr or .exr), checked from its header.
pub const MAX_ENV_SIDE: u32 = 16384;

/// The most pixels of an environment image (16384 × 4096 or 8192 × 8192), checked from its
/// header before any pixel is read.
pub const MAX_ENV_PIXELS: u64 = 1 << 26;

/// The largest light intensity and emissive strength accepted; larger values are clamped with
/// a warning, so that sums of samples stay finite in f32.
pub const MAX_INTENSITY: f32 = 1e12;

/// Checks a texture image's header size against [`MAX_IMAGE_SIDE`] and [`MAX_IMAGE_PIXELS`].
pub fn check_image_size(width: u32, height: u32) -> Result<(), String> {
    check_size(width, height, MAX_IMAGE_SIDE, MAX_IMAGE_PIXELS)
}

/// Checks an image's header size against a side and pixel limit.
pub fn check_size(width: u32, height: u32, max_side: u32, max_pixels: u64) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("the image is empty ({width}×{height})"));
    }
    if width > max_side || height > max_side || width as u64 * height as u64 > max_pixels {
        return Err(format!(
            "{width}×{height} pixels is more than the limit ({max_side} per side, \
             {max_pixels} pixels)"
        ));
    }
    Ok(())
}
