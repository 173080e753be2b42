//! PLY meshes (Turk's polygon file format, 1.0): ASCII, binary little- and big-endian.
//!
//! Reads the header's elements and properties, then every element in order: `vertex` gives
//! positions (`x y z`), normals (`nx ny nz`) and texture coordinates (`u v`, `s t` or
//! `texture_u texture_v`); `face` gives polygons (a list property `vertex_indices` or
//! `vertex_index`), fanned into triangles; other elements are read past. Writes a
//! [`MeshInput`] of one material.
//!
//! Written here rather than taken from `ply-rs`: that crate (last released 2020) builds with
//! `skeptic` and `peg` 0.6, and its errors name neither the line nor the element. Every error
//! here names the file and the header line, the ASCII line, or the element and its index, and
//! no input panics (the `mesh_files` fuzz target).

use crate::error::{Error, Result};
use crate::scene::MeshInput;
use glam::{Vec2, Vec3};
use std::path::Path;

/// A scalar type of the header.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Debug)]
struct Property {
    name: String,
    /// `Some(count type)` for a list property.
    list: Option<Scalar>,
    value: Scalar,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    line: usize,
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Format {
    Ascii,
    Little,
    Big,
}

/// The body's values, read one at a time from either encoding.
struct Body<'a> {
    format: Format,
    data: &'a [u8],
    at: usize,
    /// 1-based line of the next ASCII token.
    line: usize,
}

impl Body<'_> {
    /// The next value, as f64 (exact for every PLY integer type).
    fn next(&mut self, ty: Scalar) -> std::result::Result<f64, String> {
        if self.format == Format::Ascii {
            while self.at < self.data.len() && self.data[self.at].is_ascii_whitespace() {
                self.line += usize::from(self.data[self.at] == b'\n');
                self.at += 1;
            }
            let start = self.at;
            while self.at < self.data.len() && !self.data[self.at].is_ascii_whitespace() {
                self.at += 1;
            }
            if start == self.at {
                return Err("the file ends early".into());
            }
            let word = std::str::from_utf8(&self.data[start..self.at]).unwrap_or("?");
            return word.parse::<f64>().map_err(|_| format!("`{word}` is not a number"));
        }
        let n = ty.size();
        let Some(bytes) = self.data.get(self.at..self.at + n) else {
            return Err(format!("the file ends early (byte {} of {})", self.at, self.data.len()));
        };
        self.at += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(bytes);
        if self.format == Format::Big {
            b[..n].reverse();
        }
        let [b0, b1, b2, b3, ..] = b;
        Ok(match ty {
            Scalar::I8 => f64::from(b0 as i8),
            Scalar::U8 => f64::from(b0),
            Scalar::I16 => f64::from(i16::from_le_bytes([b0, b1])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b0, b1])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b0, b1, b2, b3])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b0, b1, b2, b3])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b0, b1, b2, b3])),
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }

    /// Where the reader is, for messages.
    fn line(&self) -> usize {
        if self.format == Format::Ascii {
            self.line
        } else {
            0
        }
    }
}

/// The header's format and elements, and the byte where the body starts.
fn parse_header(path: &Path, data: &[u8]) -> Result<(Format, Vec<Element>, usize, usize)> {
    let err = |line: usize, m: String| Error::parse(path, line, m);
    if !data.starts_with(b"ply") {
        return Err(err(1, "not a PLY file (it does not start with `ply`)".into()));
    }
    let (mut at, mut line) = (0, 0);
    let (mut format, mut elements) = (None, Vec::<Element>::new());
    loop {
        let Some(len) = data[at..].iter().position(|&b| b == b'\n') else {
            return Err(err(line + 1, "the header has no `end_header` line".into()));
        };
        let text = String::from_utf8_lossy(&data[at..at + len]);
        at += len + 1;
        line += 1;
        let words: Vec<&str> = text.split_whitespace().collect();
        match words.as_slice() {
            ["ply"] if line == 1 => {}
            ["end_header"] => break,
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, version] => {
                if !version.starts_with('1') {
                    return Err(err(line, format!("PLY version {version} is not read (1.0 is)")));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    other => return Err(err(line, format!("unknown format `{other}`"))),
                });
            }
            ["element", name, count] => {
                let count = count.parse().map_err(|_| err(line, format!("`{count}` is not an element count")))?;
                elements.push(Element { name: (*name).to_string(), count, properties: Vec::new(), line });
            }
            ["property", rest @ ..] => {
                let Some(element) = elements.last_mut() else {
                    return Err(err(line, "a property before any element".into()));
                };
                let ty = |s: &str| Scalar::parse(s).ok_or_else(|| err(line, format!("unknown property type `{s}`")));
                let property = match rest {
                    ["list", count, value, name] => {
                        let count = ty(count)?;
                        if matches!(count, Scalar::F32 | Scalar::F64) {
                            return Err(err(line, "a list's count must be an integer type".into()));
                        }
                        Property { name: (*name).to_string(), list: Some(count), value: ty(value)? }
                    }
                    [value, name] => Property { name: (*name).to_string(), list: None, value: ty(value)? },
                    _ => return Err(err(line, format!("cannot read the property `{}`", text.trim()))),
                };
                element.properties.push(property);
            }
            _ => {
                return Err(err(
                    line,
                    format!("cannot read the header line `{}` (is `end_header` missing?)", text.trim()),
                ))
            }
        }
    }
    let format = format.ok_or_else(|| err(line, "the header has no `format` line".into()))?;
    Ok((format, elements, at, line + 1))
}

/// Loads the PLY file at `path` as a mesh of `material`. Every file read is added to `inputs`.
pub fn load_ply(
    path: &Path,
    material: u32,
    warnings: &mut Vec<String>,
    inputs: &mut Vec<std::path::PathBuf>,
) -> Result<MeshInput> {
    let data = crate::files::read_input(path, "a mesh (PLY)", crate::files::MAX_MESH_FILE)?;
    inputs.push(path.to_path_buf());
    let (format, elements, start, first_line) = parse_header(path, &data)?;
    let mut body = Body { format, data: &data, at: start, line: first_line };
    let mut mesh = MeshInput { source: path.display().to_string(), ..Default::default() };
    let mut skipped_faces = 0u64;
    for e in &elements {
        let fail = |body: &Body, i: u64, m: String| {
            Error::parse(
                path,
                body.line(),
                format!("element `{}` {i} (of {}, header line {}): {m}", e.name, e.count, e.line),
            )
        };
        if e.properties.is_empty() {
            continue;
        }
        // Every instance takes at least one byte: a count beyond the file is a lie, not a loop.
        if e.count > data.len() as u64 {
            return Err(Error::parse(
                path,
                e.line,
                format!("element `{}` claims {} instances, more than the file's bytes", e.name, e.count),
            ));
        }
        let slot =
            |names: &[&str]| e.properties.iter().position(|p| p.list.is_none() && names.contains(&p.name.as_str()));
        let xyz = [slot(&["x"]), slot(&["y"]), slot(&["z"])];
        let nxyz = [slot(&["nx"]), slot(&["ny"]), slot(&["nz"])];
        let uv = [slot(&["u", "s", "texture_u", "texture_s"]), slot(&["v", "t", "texture_v", "texture_t"])];
        let is_vertex = e.name == "vertex";
        if is_vertex && xyz.iter().any(Option::is_none) {
            return Err(Error::parse(path, e.line, "the `vertex` element needs properties x, y and z"));
        }
        let own_normals = is_vertex && nxyz.iter().all(Option::is_some);
        let faces = e
            .properties
            .iter()
            .position(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"));
        let is_face = e.name == "face" && faces.is_some();
        let mut values = vec![0.0f64; e.properties.len()];
        let mut polygon: Vec<u32> = Vec::new();
        for i in 0..e.count {
            for (k, p) in e.properties.iter().enumerate() {
                match p.list {
                    None => values[k] = body.next(p.value).map_err(|m| fail(&body, i, m))?,
                    Some(count_type) => {
                        let n = body.next(count_type).map_err(|m| fail(&body, i, m))?;
                        if !(n >= 0.0 && n.fract() == 0.0 && n <= 65_535.0) {
                            return Err(fail(&body, i, format!("list `{}` has {n} entries", p.name)));
                        }
                        let keep = is_face && Some(k) == faces;
                        polygon.clear();
                        for _ in 0..n as usize {
                            let v = body.next(p.value).map_err(|m| fail(&body, i, m))?;
                            if keep {
                                if !(v >= 0.0 && v.fract() == 0.0 && v < mesh.positions.len() as f64) {
                                    return Err(fail(
                                        &body,
                                        i,
                                        format!(
                                            "vertex index {v} is not one of the {} vertices read before it",
                                            mesh.positions.len()
                                        ),
                                    ));
                                }
                                polygon.push(v as u32);
                            }
                        }
                        if keep {
                            if polygon.len() < 3 {
                                skipped_faces += 1;
                            }
                            for j in 2..polygon.len() {
                                mesh.triangles.push([polygon[0], polygon[j - 1], polygon[j]]);
                            }
                        }
                    }
                }
            }
            if is_vertex {
                let get = |s: [Option<usize>; 3]| Vec3::from_array(s.map(|k| k.map_or(0.0, |k| values[k] as f32)));
                let p = get(xyz);
                if !p.is_finite() {
                    return Err(fail(&body, i, format!("the vertex is {p}, not finite")));
                }
                mesh.positions.push(p);
                let n = get(nxyz);
                // A column starts with the first vertex element that has it: pad what came before.
                // An element without it adds nothing here; the padding after the loop (or before
                // a later element that has it) gives its vertices zeros.
                let before = mesh.positions.len() - 1;
                if own_normals {
                    mesh.normals.resize(before, Vec3::ZERO);
                    mesh.zero_normals += u64::from(n.try_normalize().is_none());
                    mesh.normals.push(if n.try_normalize().is_some() { n } else { Vec3::ZERO });
                }
                if let [Some(u), Some(v)] = uv {
                    let t = Vec2::new(values[u] as f32, values[v] as f32);
                    mesh.texcoords.resize(before, Vec2::ZERO);
                    mesh.texcoords.push(if t.is_finite() { t } else { Vec2::ZERO });
                }
            }
        }
    }
    // A later vertex element may lack a column an earlier one had.
    if !mesh.normals.is_empty() {
        mesh.normals.resize(mesh.positions.len(), Vec3::ZERO);
    }
    if !mesh.texcoords.is_empty() {
        mesh.texcoords.resize(mesh.positions.len(), Vec2::ZERO);
    }
    if skipped_faces > 0 {
        warnings.push(format!("{}: {skipped_faces} faces with fewer than 3 vertices were skipped", path.display()));
    }
    if mesh.zero_normals > 0 {
        warnings.push(format!(
            "{}: {} vertex normals have zero length; faces shade with their geometric normal there",
            path.display(),
            mesh.zero_normals
        ));
    }
    if mesh.triangles.is_empty() {
        return Err(Error::parse(path, 0, "the file has no faces (a `face` element with a `vertex_indices` list)"));
    }
    mesh.material = vec![material; mesh.triangles.len()];
    Ok(mesh)
}
