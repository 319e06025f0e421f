//! Texture packing: every (image, color space) pair a material uses becomes one RGBA8 mip
//! chain in a single texel buffer, within the device's memory budget.

use crate::cl::types::*;
use crate::scene::{MAX_TEXTURE_SIDE, Scene, Wrap, mip_chain};
use rayon::prelude::*;
use std::collections::HashMap;

/// Textures as the device stores them: every (image, color space) pair used by a material
/// becomes one RGBA8 mip chain in a single texel buffer; materials point at `refs`.
#[derive(Clone, Debug, Default)]
pub struct TexturePack {
    /// One descriptor per texture.
    pub textures: Vec<DeviceTexture>,
    /// One entry per `Scene::texture_refs` entry.
    pub refs: Vec<DeviceTexRef>,
    /// RGBA8 texels (R in the low byte) of every level of every texture.
    pub texels: Vec<u32>,
    /// The largest side kept (smaller than [`MAX_TEXTURE_SIDE`] when the budget forced it).
    pub max_side: u32,
}

fn wrap_code(w: Wrap) -> i32 {
    match w {
        Wrap::Repeat => WRAP_REPEAT,
        Wrap::Clamp => WRAP_CLAMP,
        Wrap::Mirror => WRAP_MIRROR,
    }
}

impl TexturePack {
    /// Packs the scene's textures. Mip chains are box-filtered on the host (in linear space for
    /// sRGB textures); levels above [`MAX_TEXTURE_SIDE`] are dropped, and while the texels would
    /// exceed `budget_bytes` the largest side allowed is halved.
    pub fn new(scene: &Scene, budget_bytes: usize) -> Self {
        let mut keys: Vec<(u32, bool)> = Vec::new();
        let mut index: HashMap<(u32, bool), u32> = HashMap::new();
        for r in &scene.texture_refs {
            index.entry((r.image, r.srgb)).or_insert_with(|| {
                keys.push((r.image, r.srgb));
                keys.len() as u32 - 1
            });
        }
        // Texels of a chain whose level 0 is capped at `side`.
        let chain_texels = |w: u32, h: u32, side: u32| -> usize {
            let (mut w, mut h) = (w, h);
            while w > side || h > side {
                w = (w / 2).max(1);
                h = (h / 2).max(1);
            }
            let mut n = 0usize;
            loop {
                n += (w * h) as usize;
                if w == 1 && h == 1 {
                    return n;
                }
                w = (w / 2).max(1);
                h = (h / 2).max(1);
            }
        };
        let mut max_side = MAX_TEXTURE_SIDE;
        while max_side > 1 {
            let total: usize = keys
                .iter()
                .map(|&(i, _)| {
                    let im = &scene.images[i as usize];
                    chain_texels(im.width, im.height, max_side)
                })
                .sum();
            if total * 4 <= budget_bytes {
                break;
            }
            max_side /= 2;
        }
        let chains: Vec<Vec<crate::scene::MipLevel>> = keys
            .par_iter()
            .map(|&(i, srgb)| mip_chain(&scene.images[i as usize], srgb, max_side))
            .collect();
        let mut textures = Vec::with_capacity(chains.len());
        let mut texels = Vec::new();
        for (chain, &(_, srgb)) in chains.iter().zip(&keys) {
            textures.push(DeviceTexture {
                offset: texels.len() as u32,
                width: chain[0].width,
                height: chain[0].height,
                flags: chain.len() as u32 | if srgb { TEXTURE_SRGB } else { 0 },
            });
            for level in chain {
                texels.extend(level.rgba.iter().map(|&t| u32::from_le_bytes(t)));
            }
        }
        let refs = scene
            .texture_refs
            .iter()
            .map(|r| {
                let [a, b] = r.transform.rows();
                let det = (a[0] * b[1] - a[1] * b[0]).abs().max(1e-12);
                DeviceTexRef {
                    m0: [a[0], a[1], a[2], f32::from_bits(r.tex_coord)],
                    m1: [b[0], b[1], b[2], 0.5 * det.log2()],
                    info: [
                        index[&(r.image, r.srgb)] as i32,
                        wrap_code(r.wrap_s),
                        wrap_code(r.wrap_t),
                        if r.nearest { TEXREF_NEAREST } else { 0 }
                            | if r.mipmaps { 0 } else { TEXREF_NO_MIPS },
                    ],
                }
            })
            .collect();
        Self {
            textures,
            refs,
            texels,
            max_side,
        }
    }

    /// Bytes of texel memory on the device.
    pub fn bytes(&self) -> usize {
        self.texels.len() * 4
    }
}
