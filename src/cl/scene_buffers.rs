//! The scene on the device: its buffers ([`SceneBuffers`]), which of the BVH's node arrays
//! they hold ([`NodeForms`]), and the environment map's ([`EnvBuffers`]).

use super::Buffer;
use super::types::*;

/// The environment map on the device (a 1×1 black placeholder when there is none).
pub struct EnvBuffers {
    /// Constants.
    pub info: DeviceEnvironment,
    /// RGB f32 texels.
    pub texels: Buffer<f32>,
    /// Cumulative row probabilities.
    pub marginal: Buffer<f32>,
    /// Cumulative column probabilities per row.
    pub conditional: Buffer<f32>,
}

/// Which node arrays of the BVH a scene's buffers hold: the binary one (the wavefront's
/// `extend` and `connect`, `trace_closest` and `trace_any`) and the 4-wide one (the
/// megakernel's, `trace_closest_wide` and `trace_any_wide`). The array left out is a
/// placeholder of one node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeForms {
    /// The binary nodes.
    pub binary: bool,
    /// The 4-wide nodes.
    pub wide: bool,
}

impl NodeForms {
    /// Both arrays (tests and `bench trace`, which trace through either).
    pub const BOTH: Self = Self {
        binary: true,
        wide: true,
    };

    /// Neither array.
    pub const NONE: Self = Self {
        binary: false,
        wide: false,
    };

    /// Those the kernels in use traverse: the megakernel's wide nodes or the wavefront's
    /// binary ones.
    pub fn for_kernels(megakernel: bool) -> Self {
        Self {
            binary: !megakernel,
            wide: megakernel,
        }
    }

    /// Both this one's arrays and `other`'s.
    pub fn with(self, other: Self) -> Self {
        Self {
            binary: self.binary || other.binary,
            wide: self.wide || other.wide,
        }
    }

    /// This one's arrays that `have` lacks.
    pub fn beyond(self, have: Self) -> Self {
        Self {
            binary: self.binary && !have.binary,
            wide: self.wide && !have.wide,
        }
    }
}

/// The scene on the device: BVH, triangles, shading data, materials and lights.
pub struct SceneBuffers {
    /// Which of the two node arrays are real (the other a placeholder).
    pub forms: NodeForms,
    /// BVH nodes (a placeholder unless `forms.binary`).
    pub nodes: Buffer<DeviceBvhNode>,
    /// The same BVH collapsed to 4-wide nodes (the megakernel's; a placeholder unless
    /// `forms.wide`).
    pub wide_nodes: Buffer<DeviceWideNode>,
    /// Triangles in shading order (the flat BVH's order, or instance by instance).
    pub triangles: Buffer<DeviceTriangle>,
    /// Two levels: the instances in top-level order (one placeholder when flat).
    pub instances: Buffer<DeviceInstance>,
    /// Two levels: every distinct mesh's object-space triangles in its bottom level's order
    /// (one placeholder when flat).
    pub object_triangles: Buffer<DeviceTriangle>,
    /// Corner normals in BVH order.
    pub shading: Buffer<DeviceTriShading>,
    /// Texture coordinates in BVH order (one placeholder element when no material samples a
    /// texture).
    pub uvs: Buffer<DeviceTriUvs>,
    /// Tangents in BVH order (one placeholder element without normal maps).
    pub tangents: Buffer<DeviceTriTangents>,
    /// Vertex colours in BVH order (one placeholder element when no mesh has them).
    pub colors: Buffer<DeviceTriColors>,
    /// Texture references (materials index them).
    pub tex_refs: Buffer<DeviceTexRef>,
    /// Texture descriptors.
    pub textures: Buffer<DeviceTexture>,
    /// RGBA8 texels of every mip level of every texture.
    pub texels: Buffer<u32>,
    /// Materials.
    pub materials: Buffer<DeviceMaterial>,
    /// Lights (emissive triangles first, then punctual lights, then the environment map).
    pub lights: Buffer<DeviceLight>,
    /// Cumulative selection probabilities of the lights.
    pub light_cdf: Buffer<f32>,
}

impl SceneBuffers {
    /// Bytes of every buffer: what the scene takes on the device.
    pub fn bytes(&self) -> usize {
        self.nodes.bytes()
            + self.wide_nodes.bytes()
            + self.triangles.bytes()
            + self.instances.bytes()
            + self.object_triangles.bytes()
            + self.shading.bytes()
            + self.uvs.bytes()
            + self.tangents.bytes()
            + self.colors.bytes()
            + self.tex_refs.bytes()
            + self.textures.bytes()
            + self.texels.bytes()
            + self.materials.bytes()
            + self.lights.bytes()
            + self.light_cdf.bytes()
    }
}
