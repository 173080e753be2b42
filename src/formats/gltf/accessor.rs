//! glTF accessors read from their buffers with every bound checked: the element's size against
//! the view's stride, the last element against the view's end, the view against its buffer, and
//! indices against the vertex count. Floats are read as they are; normalised integers (texture
//! coordinates may be stored so) are scaled to [0, 1] or [−1, 1] as the spec says.

use crate::error::{Error, Result};
use gltf::accessor::{DataType, Dimensions};
use std::path::Path;

/// The bytes of each element of accessor `a` (its view's slice, stride and element size).
fn elements<'b>(
    a: &gltf::Accessor,
    buffers: &'b [Vec<u8>],
    path: &Path,
    what: &str,
) -> Result<(Vec<&'b [u8]>, DataType)> {
    let err = |m: String| Error::parse(path, 0, format!("{what}: accessor {}: {m}", a.index()));
    if a.sparse().is_some() {
        return Err(err("sparse accessors are not read".into()));
    }
    let Some(view) = a.view() else { return Err(err("it has no buffer view".into())) };
    let dims = match a.dimensions() {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 => 4,
        other => return Err(err(format!("{other:?} elements are not vertex data"))),
    };
    let element = a.data_type().size() * dims;
    let stride = view.stride().unwrap_or(element);
    if stride < element {
        return Err(err(format!("its view's stride {stride} is shorter than an element ({element} bytes)")));
    }
    let buffer = &buffers[view.buffer().index()];
    let slice = view
        .offset()
        .checked_add(view.length())
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| err(format!("buffer view {} runs past its buffer", view.index())))?;
    let count = a.count();
    let fits = count == 0
        || (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(a.offset().checked_add(element)?))
            .is_some_and(|end| end <= slice.len());
    if !fits {
        return Err(err(format!("{count} elements run past the end of buffer view {}", view.index())));
    }
    Ok((
        (0..count).map(|i| &slice[a.offset() + i * stride..a.offset() + i * stride + element]).collect(),
        a.data_type(),
    ))
}

/// Component `k` of an element as f32, normalised when `normalized`.
fn component(bytes: &[u8], ty: DataType, k: usize, normalized: bool) -> f32 {
    let at = k * ty.size();
    let b = |i: usize| bytes[at + i];
    let (value, scale) = match ty {
        DataType::I8 => (f32::from(b(0) as i8), 127.0),
        DataType::U8 => (f32::from(b(0)), 255.0),
        DataType::I16 => (f32::from(i16::from_le_bytes([b(0), b(1)])), 32767.0),
        DataType::U16 => (f32::from(u16::from_le_bytes([b(0), b(1)])), 65535.0),
        DataType::U32 => (u32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f32, 1.0),
        DataType::F32 => return f32::from_le_bytes([b(0), b(1), b(2), b(3)]),
    };
    if normalized {
        (value / scale).max(-1.0)
    } else {
        value
    }
}

/// Accessor `a` as N-component float vectors (positions, normals: VEC3; texture coordinates: VEC2).
pub fn read_f32<const N: usize>(
    a: &gltf::Accessor,
    buffers: &[Vec<u8>],
    path: &Path,
    what: &str,
) -> Result<Vec<[f32; N]>> {
    let want = if N == 3 { Dimensions::Vec3 } else { Dimensions::Vec2 };
    if a.dimensions() != want {
        return Err(Error::parse(
            path,
            0,
            format!("{what}: accessor {} holds {:?}, not {want:?}", a.index(), a.dimensions()),
        ));
    }
    let (elements, ty) = elements(a, buffers, path, what)?;
    if ty != DataType::F32 && !a.normalized() {
        return Err(Error::parse(
            path,
            0,
            format!("{what}: accessor {} holds unnormalised {ty:?}, not floats", a.index()),
        ));
    }
    Ok(elements.iter().map(|e| std::array::from_fn(|k| component(e, ty, k, a.normalized()))).collect())
}

/// Accessor `a` as vertex indices, each checked to be below `vertices`.
pub fn read_indices(
    a: &gltf::Accessor,
    buffers: &[Vec<u8>],
    path: &Path,
    what: &str,
    vertices: usize,
) -> Result<Vec<u32>> {
    let (elements, ty) = elements(a, buffers, path, what)?;
    if a.dimensions() != Dimensions::Scalar || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32) {
        return Err(Error::parse(
            path,
            0,
            format!("{what}: index accessor {} is not unsigned integer scalars", a.index()),
        ));
    }
    elements
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let v = component(e, ty, 0, false) as u64;
            let v = if ty == DataType::U32 { u64::from(u32::from_le_bytes([e[0], e[1], e[2], e[3]])) } else { v };
            if v < vertices as u64 {
                Ok(v as u32)
            } else {
                Err(Error::parse(
                    path,
                    0,
                    format!("{what}: index {i} of accessor {} is {v}, but there are {vertices} vertices", a.index()),
                ))
            }
        })
        .collect()
}
