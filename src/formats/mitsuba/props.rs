//! A Mitsuba element's properties: `<float name value>`, `<integer>`, `<boolean>`, `<string>`,
//! `<rgb>`, `<spectrum>`, `<point>`, `<vector>` and `<transform>`, read with `$param`
//! substitution and with names compared the way both generations write them: `toWorld` (0.5,
//! 0.6) and `to_world` (2.x, 3.x) are one property, as are `intIOR` and `int_ior`.

use crate::error::{Error, Result};
use glam::{Affine3A, Mat4, Quat, Vec3};
use roxmltree::{Node, NodeId};
use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// A property name as compared: lower case, without underscores.
pub fn key(name: &str) -> String {
    name.chars().filter(|c| *c != '_').flat_map(char::to_lowercase).collect()
}

/// What reading properties needs: the file, its text positions and the `$param` values; it
/// notes which elements were converted and which of their properties were read, so that
/// [`Reader::unread`] can name the rest.
pub struct Reader<'a> {
    pub path: &'a Path,
    pub doc: &'a roxmltree::Document<'a>,
    pub params: HashMap<String, String>,
    /// Property elements read.
    pub read: RefCell<HashSet<NodeId>>,
    /// Plugin elements converted (their unread properties are warned of).
    pub visited: RefCell<HashSet<NodeId>>,
}

impl Reader<'_> {
    /// The 1-based line of `node`.
    pub fn line(&self, node: Node) -> usize {
        self.doc.text_pos_at(node.range().start).row as usize
    }

    /// An error at `node`.
    pub fn error(&self, node: Node, message: impl Into<String>) -> Error {
        Error::parse(self.path, self.line(node), message.into())
    }

    /// Attribute `name` of `node` with every `$param` replaced by its value.
    pub fn attr(&self, node: Node, name: &str) -> Result<Option<String>> {
        let Some(raw) = node.attribute(name) else { return Ok(None) };
        if !raw.contains('$') {
            return Ok(Some(raw.to_string()));
        }
        let mut out = String::new();
        let mut rest = raw;
        while let Some(at) = rest.find('$') {
            out.push_str(&rest[..at]);
            let tail = &rest[at + 1..];
            let len = tail.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(tail.len());
            let param = &tail[..len];
            let value = self.params.get(param).ok_or_else(|| {
                self.error(node, format!("`${param}` has no value (give it a <default name=\"{param}\" value=\"…\"/>)"))
            })?;
            out.push_str(value);
            rest = &tail[len..];
        }
        out.push_str(rest);
        Ok(Some(out))
    }

    /// The child property element of `node` named `name` (compared by [`key`]), noted as read.
    pub fn prop<'n>(&self, node: Node<'n, 'n>, name: &str) -> Option<Node<'n, 'n>> {
        let want = key(name);
        self.visited.borrow_mut().insert(node.id());
        let found =
            node.children().filter(Node::is_element).find(|c| c.attribute("name").is_some_and(|n| key(n) == want));
        if let Some(p) = found {
            self.read.borrow_mut().insert(p.id());
        }
        found
    }

    /// The properties of converted elements that nothing read: (line, property, element).
    pub fn unread(&self) -> Vec<(usize, String, String)> {
        let (read, visited) = (self.read.borrow(), self.visited.borrow());
        let mut out = Vec::new();
        for parent in self.doc.descendants().filter(|n| visited.contains(&n.id()) && n.tag_name().name() != "film") {
            for p in parent.children().filter(|c| c.is_element() && !read.contains(&c.id())) {
                let Some(name) = p.attribute("name") else { continue };
                if matches!(
                    p.tag_name().name(),
                    "bsdf" | "texture" | "ref" | "emitter" | "rfilter" | "sampler" | "film" | "medium"
                ) {
                    continue;
                }
                let what =
                    format!("<{} type=\"{}\">", parent.tag_name().name(), parent.attribute("type").unwrap_or(""));
                out.push((self.line(p), name.to_string(), what));
            }
        }
        out
    }

    /// Numbers in `text`, separated by commas or spaces.
    pub fn numbers(&self, node: Node, text: &str) -> Result<Vec<f32>> {
        text.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|w| !w.is_empty())
            .map(|w| w.parse::<f32>().map_err(|_| self.error(node, format!("`{w}` is not a number"))))
            .collect()
    }

    /// A number attribute `name` of `node`.
    fn number(&self, node: Node, name: &str) -> Result<Option<f32>> {
        match self.attr(node, name)? {
            None => Ok(None),
            Some(v) => {
                v.trim().parse().map(Some).map_err(|_| self.error(node, format!("{name}=\"{v}\" is not a number")))
            }
        }
    }

    /// A float (or integer) property, or `default`.
    pub fn float(&self, node: Node, name: &str, default: f32) -> Result<f32> {
        match self.prop(node, name) {
            None => Ok(default),
            Some(p) => {
                let v = self.number(p, "value")?.ok_or_else(|| self.error(p, format!("`{name}` has no value")))?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(self.error(p, format!("`{name}` must be finite")))
                }
            }
        }
    }

    /// A string property.
    pub fn string(&self, node: Node, name: &str) -> Result<Option<String>> {
        self.prop(node, name).map_or(Ok(None), |p| self.attr(p, "value"))
    }

    /// A boolean property, or `default`.
    pub fn boolean(&self, node: Node, name: &str, default: bool) -> Result<bool> {
        Ok(self.string(node, name)?.map_or(default, |v| v == "true" || v == "1"))
    }

    /// A colour from an `<rgb>`, `<spectrum>` (one value, or λ:value pairs averaged), `<srgb>`
    /// (decoded) or `<float>` element.
    pub fn colour_of(&self, p: Node) -> Result<Vec3> {
        let value = self.attr(p, "value")?.unwrap_or_default();
        let v = match p.tag_name().name() {
            "rgb" | "color" => {
                let n = self.numbers(p, &value)?;
                match n.as_slice() {
                    [g] => Vec3::splat(*g),
                    [r, g, b] => Vec3::new(*r, *g, *b),
                    _ => return Err(self.error(p, format!("rgb value=\"{value}\" is not one or three numbers"))),
                }
            }
            "srgb" => {
                let n = self.numbers(p, &value)?;
                let [r, g, b] = n[..] else {
                    return Err(self.error(p, format!("srgb value=\"{value}\" is not three numbers")));
                };
                Vec3::new(r, g, b).map(crate::texture::srgb_to_linear)
            }
            "spectrum" => {
                if value.contains(':') {
                    let pairs: Vec<f32> = value
                        .split(',')
                        .map(|pair| pair.split(':').nth(1).unwrap_or("").trim().parse::<f32>())
                        .collect::<std::result::Result<_, _>>()
                        .map_err(|_| self.error(p, format!("spectrum value=\"{value}\" is not λ:value pairs")))?;
                    Vec3::splat(pairs.iter().sum::<f32>() / pairs.len().max(1) as f32)
                } else {
                    let n = self.numbers(p, &value)?;
                    match n.as_slice() {
                        [g] => Vec3::splat(*g),
                        [r, g, b] => Vec3::new(*r, *g, *b),
                        _ => return Err(self.error(p, format!("spectrum value=\"{value}\" is not read"))),
                    }
                }
            }
            "float" | "integer" => Vec3::splat(self.number(p, "value")?.unwrap_or(0.0)),
            other => return Err(self.error(p, format!("<{other}> is not a colour"))),
        };
        if v.is_finite() && v.min_element() >= 0.0 {
            Ok(v)
        } else {
            Err(self.error(p, format!("the colour {v} must be finite and not negative")))
        }
    }

    /// A point or vector property (`value="x y z"`, or `x`, `y`, `z` attributes).
    pub fn point(&self, node: Node, name: &str) -> Result<Option<Vec3>> {
        let Some(p) = self.prop(node, name) else { return Ok(None) };
        self.xyz(p, 0.0).map(Some)
    }

    /// The `x`, `y`, `z` attributes of `node` (or its `value`), each `default` when absent.
    fn xyz(&self, node: Node, default: f32) -> Result<Vec3> {
        if let Some(v) = self.attr(node, "value")? {
            let n = self.numbers(node, &v)?;
            return match n.as_slice() {
                [s] => Ok(Vec3::splat(*s)),
                [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
                _ => Err(self.error(node, format!("value=\"{v}\" is not one or three numbers"))),
            };
        }
        Ok(Vec3::new(
            self.number(node, "x")?.unwrap_or(default),
            self.number(node, "y")?.unwrap_or(default),
            self.number(node, "z")?.unwrap_or(default),
        ))
    }

    /// The `<transform name=NAME>` of `node` (identity when absent): its `translate`, `rotate`,
    /// `scale`, `matrix` and `lookat` children applied in order, each after the ones before.
    pub fn transform(&self, node: Node, name: &str) -> Result<Affine3A> {
        let Some(t) = self.prop(node, name) else { return Ok(Affine3A::IDENTITY) };
        let mut m = Affine3A::IDENTITY;
        for step in t.children().filter(Node::is_element) {
            let next = match step.tag_name().name() {
                "translate" => Affine3A::from_translation(self.xyz(step, 0.0)?),
                "scale" => Affine3A::from_scale(self.xyz(step, 1.0)?),
                "rotate" => {
                    let angle = self.number(step, "angle")?.unwrap_or(0.0);
                    let axis = match self.attr(step, "axis")? {
                        Some(a) => Vec3::from_slice(
                            &self.numbers(step, &a)?.into_iter().chain([0.0; 3]).take(3).collect::<Vec<_>>(),
                        ),
                        None => self.xyz(step, 0.0)?,
                    };
                    let axis =
                        axis.try_normalize().ok_or_else(|| self.error(step, "a rotation needs a non-zero axis"))?;
                    Affine3A::from_quat(Quat::from_axis_angle(axis, angle.to_radians()))
                }
                "matrix" => {
                    let v = self.attr(step, "value")?.unwrap_or_default();
                    let n = self.numbers(step, &v)?;
                    let rows: [f32; 16] = match n.len() {
                        16 => n.try_into().unwrap_or([0.0; 16]),
                        9 => [n[0], n[1], n[2], 0.0, n[3], n[4], n[5], 0.0, n[6], n[7], n[8], 0.0, 0.0, 0.0, 0.0, 1.0],
                        _ => return Err(self.error(step, "a matrix has 16 (or 9) numbers, row by row")),
                    };
                    let mat = Mat4::from_cols_array(&rows).transpose();
                    if (mat.row(3) - glam::Vec4::W).abs().max_element() > 1e-6 {
                        return Err(self
                            .error(step, "a projective matrix does not place a shape (the last row must be 0 0 0 1)"));
                    }
                    Affine3A::from_mat4(mat)
                }
                "lookat" | "lookAt" => {
                    let get = |a: &str| -> Result<Vec3> {
                        let v = self.attr(step, a)?.ok_or_else(|| self.error(step, format!("lookat needs `{a}`")))?;
                        let n = self.numbers(step, &v)?;
                        (n.len() == 3)
                            .then(|| Vec3::from_slice(&n))
                            .ok_or_else(|| self.error(step, format!("`{a}` is three numbers")))
                    };
                    let (origin, target) = (get("origin")?, get("target")?);
                    let up = if step.attribute("up").is_some() { get("up")? } else { Vec3::Y };
                    let dir = (target - origin)
                        .try_normalize()
                        .ok_or_else(|| self.error(step, "lookat's target is its origin"))?;
                    let left = up
                        .cross(dir)
                        .try_normalize()
                        .ok_or_else(|| self.error(step, "lookat's up is along its view"))?;
                    Affine3A::from_cols(left.into(), dir.cross(left).into(), dir.into(), origin.into())
                }
                other => return Err(self.error(step, format!("<{other}> is not a transform step"))),
            };
            m = next * m;
        }
        if !(m.matrix3.is_finite() && m.translation.is_finite()) {
            return Err(self.error(t, "the transform is not finite"));
        }
        Ok(m)
    }
}
