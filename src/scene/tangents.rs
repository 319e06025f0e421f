//! Tangent generation for normal-mapped primitives without `TANGENT`: MikkTSpace (the
//! algorithm glTF prescribes), through the `bevy_mikktspace` crate.
//!
//! glTF's texture coordinates grow downwards while normal maps store +Y as "up" in the image,
//! so the generator sees (u, 1 − v); the result then satisfies glTF's
//! `bitangent = cross(normal, tangent.xyz) × tangent.w`, the bitangent pointing up the image.

use bevy_mikktspace::{Geometry, TangentSpace, generate_tangents};
use glam::{Vec2, Vec3, Vec4};

struct Faces<'a> {
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    uvs: &'a [Vec2],
    indices: &'a [[u32; 3]],
    out: Vec<[Vec4; 3]>,
}

impl Faces<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.indices[face][vert] as usize
    }

    fn face_normal(&self, face: usize) -> Vec3 {
        let [a, b, c] = self.indices[face].map(|i| self.positions[i as usize]);
        (b - a).cross(c - a).normalize_or(Vec3::Z)
    }
}

impl Geometry for Faces<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.vertex(face, vert)].into()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        let n = self
            .normals
            .get(self.vertex(face, vert))
            .copied()
            .unwrap_or(Vec3::ZERO);
        if n == Vec3::ZERO {
            self.face_normal(face).into()
        } else {
            n.into()
        }
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv = self.uvs[self.vertex(face, vert)];
        [uv.x, 1.0 - uv.y]
    }

    fn set_tangent(&mut self, tangent: Option<TangentSpace>, face: usize, vert: usize) {
        self.out[face][vert] = tangent.map_or(Vec4::ZERO, |t| Vec4::from(t.tangent_encoded()));
    }
}

/// MikkTSpace tangents at the corners of `indices` (zero where none could be made, e.g.
/// degenerate UVs with no neighbour to borrow from). `normals` may be empty (flat shading).
pub fn generate(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: &[Vec2],
    indices: &[[u32; 3]],
) -> Vec<[Vec4; 3]> {
    let mut faces = Faces {
        positions,
        normals,
        uvs,
        indices,
        out: vec![[Vec4::ZERO; 3]; indices.len()],
    };
    if uvs.len() < positions.len() || generate_tangents(&mut faces).is_err() {
        return vec![[Vec4::ZERO; 3]; indices.len()];
    }
    faces.out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quad_in_the_xy_plane_gets_tangent_x_and_bitangent_up_the_image() {
        // u grows along +X, v (downwards in the image) along -Y: "up the image" is +Y.
        let positions = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let normals = [Vec3::Z; 4];
        let uvs = [
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ];
        let t = generate(&positions, &normals, &uvs, &[[0, 1, 2], [0, 2, 3]]);
        for corner in t.iter().flatten() {
            assert!((corner.truncate() - Vec3::X).length() < 1e-5, "{corner}");
            let bitangent = Vec3::Z.cross(corner.truncate()) * corner.w;
            assert!((bitangent - Vec3::Y).length() < 1e-5, "{bitangent}");
        }
    }
}
