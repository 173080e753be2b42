//! Affine transforms of meshes: what a TOML `[[mesh]]`, a glTF node or a Mitsuba `toWorld` says,
//! applied to a [`MeshInput`] — positions as points, normals by the inverse transpose, and the
//! winding reversed where the transform mirrors (so that the front face, the one that emits,
//! stays on the same side of the surface).

use crate::error::{Error, Result};
use crate::scene::MeshInput;
use glam::{Affine3A, Mat3, Mat4, Quat, Vec3};

/// An affine transform of object space into world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform(pub Affine3A);

impl Default for Transform {
    fn default() -> Self {
        Transform(Affine3A::IDENTITY)
    }
}

impl Transform {
    /// Uniform scale, then translation (the original TOML `scale` and `translate`).
    #[must_use]
    pub fn scale_translate(scale: f32, translate: Vec3) -> Transform {
        Transform(Affine3A::from_scale_rotation_translation(Vec3::splat(scale), Quat::IDENTITY, translate))
    }

    /// A transform from a 4×4 matrix given row by row (the last row must be 0 0 0 1); `field`
    /// names it in errors.
    pub fn from_rows(field: &str, rows: &[f32; 16]) -> Result<Transform> {
        if !rows.iter().all(|x| x.is_finite()) {
            return Err(Error::setting(field, "every entry of the matrix must be finite"));
        }
        let m = Mat4::from_cols_array(rows).transpose();
        let last = m.row(3);
        if (last - glam::Vec4::W).abs().max_element() > 1e-6 {
            return Err(Error::setting(
                field,
                format!("the last row must be 0 0 0 1 (an affine transform; found {last}): projections are not meshes"),
            ));
        }
        Transform::checked(field, Affine3A::from_mat4(m))
    }

    /// `a` when it is finite and invertible, else an error naming `field`. Invertible is judged
    /// relative to the size of its columns (a scale of 10⁻⁴ is fine; a column in the plane of the
    /// other two is not).
    pub fn checked(field: &str, a: Affine3A) -> Result<Transform> {
        let m = a.matrix3;
        let (x, y, z) =
            (Vec3::from(m.x_axis).as_dvec3(), Vec3::from(m.y_axis).as_dvec3(), Vec3::from(m.z_axis).as_dvec3());
        let det = x.dot(y.cross(z));
        let size = x.length() * y.length() * z.length();
        let finite = m.is_finite() && a.translation.is_finite();
        if !finite || !(det.abs() > 1e-9 * size) {
            return Err(Error::setting(
                field,
                format!("the transform is singular or not finite (determinant {det}): it would flatten the mesh"),
            ));
        }
        Ok(Transform(a))
    }

    /// This transform applied after `first`.
    #[must_use]
    pub fn after(self, first: Transform) -> Transform {
        Transform(self.0 * first.0)
    }

    /// Where the point `p` goes.
    #[inline]
    #[must_use]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.0.transform_point3(p)
    }

    /// Where the direction `d` goes (not normalised).
    #[inline]
    #[must_use]
    pub fn vector(&self, d: Vec3) -> Vec3 {
        self.0.transform_vector3(d)
    }

    /// The matrix normals are multiplied by: the inverse transpose of the linear part.
    #[must_use]
    pub fn normal_matrix(&self) -> Mat3 {
        Mat3::from(self.0.matrix3).inverse().transpose()
    }

    /// True when the transform mirrors space (negative determinant).
    #[must_use]
    pub fn mirrors(&self) -> bool {
        self.0.matrix3.determinant() < 0.0
    }

    /// Applies the transform to every position and normal of `mesh`, reversing each triangle's
    /// winding when it mirrors. Normals of zero length stay zero (they mean "none").
    ///
    /// Positions always go through it, the identity too: x·1 + 0 turns a file's −0 into +0, and
    /// shared edges are matched by their corners' bits (`Scene::edge_uses`), so a corner written
    /// `-0.000000` in one face and `0.000000` in the next must become the same point. Normals are
    /// left as they are under a positive uniform scale (their directions do not change).
    pub fn apply(&self, mesh: &mut MeshInput) {
        for p in &mut mesh.positions {
            *p = self.point(*p);
        }
        let m = self.0.matrix3;
        if m == glam::Mat3A::from_diagonal(Vec3::splat(m.x_axis.x)) && m.x_axis.x > 0.0 {
            return;
        }
        let nm = self.normal_matrix();
        for n in &mut mesh.normals {
            *n = (nm * *n).try_normalize().unwrap_or(Vec3::ZERO);
        }
        if self.mirrors() {
            for t in &mut mesh.triangles {
                t.swap(1, 2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_rows_and_normals_stay_normal() {
        // Scale x by 2, then translate by (1, 2, 3).
        let rows = [2.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 2.0, 0.0, 0.0, 1.0, 3.0, 0.0, 0.0, 0.0, 1.0];
        let t = Transform::from_rows("m", &rows).unwrap();
        assert_eq!(t.point(Vec3::ONE), Vec3::new(3.0, 3.0, 4.0));
        // A 45° face normal in xy: scaling x by 2 tilts it toward y.
        let n = (t.normal_matrix() * Vec3::new(1.0, 1.0, 0.0)).normalize();
        let tangent = t.vector(Vec3::new(1.0, -1.0, 0.0));
        assert!(n.dot(tangent).abs() < 1e-6);
        assert!(!t.mirrors());
    }

    #[test]
    fn a_mirror_reverses_the_winding_so_the_front_stays_in_front() {
        let mut mesh = MeshInput {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            triangles: vec![[0, 1, 2]],
            material: vec![0],
            ..Default::default()
        };
        let t = Transform::checked("m", Affine3A::from_scale(Vec3::new(1.0, 1.0, -1.0))).unwrap();
        t.apply(&mut mesh);
        let [a, b, c] = mesh.triangles[0].map(|i| mesh.positions[i as usize]);
        let ng = (b - a).cross(c - a).normalize();
        assert_eq!(mesh.normals[0], -Vec3::Z);
        assert!(ng.dot(mesh.normals[0]) > 0.99, "the winding agrees with the mirrored normal");
    }

    #[test]
    fn singular_and_projective_matrices_are_refused() {
        assert!(Transform::checked("m", Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0))).is_err());
        assert!(Transform::checked("m", Affine3A::from_scale(Vec3::splat(1e-4))).is_ok());
        assert!(Transform::checked("m", Affine3A::from_scale(Vec3::splat(1e30))).is_ok());
        let mut rows = [0.0; 16];
        rows[0] = 1.0;
        rows[5] = 1.0;
        rows[10] = 1.0;
        rows[14] = 1.0; // a perspective row
        assert!(Transform::from_rows("m", &rows).is_err());
    }
}
