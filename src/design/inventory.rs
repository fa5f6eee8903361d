//! A box of objects, as a user lists them. [`parse`] reads the command-line list:
//! comma-separated items `sphere:R`, `box:XxYxZ`, `mesh:FILE.obj[@SCALE]`, `chess:PIECE`
//! (a piece of the built-in chess set) or `chess` (one side: 16 pieces), each with an
//! optional `*N` count and `/DENSITY` (metres, kg/m^3); and items that let the design
//! choose the count: `auto:sphere` (radii chosen too), `auto:sphere:R`,
//! `auto:box:XxYxZ`, `auto:mesh:FILE.obj[@SCALE]`, `auto:chess` (pieces of one side),
//! each but `auto:chess` with an optional `*N`, the most it may add (a box of blocks
//! of three sizes is three `auto:box` items).
//! [`parse_json`] reads the same from a JSON file. Errors name the item (or the
//! JSON entry and field) and say why. A mesh's file must exist when the list is read:
//! its path is taken as given (relative to the current folder, or to a JSON list's
//! folder) and nowhere else, so that the error names the path the user wrote. The
//! caller looks at the file system for the parser (a [`Look`], which the command line
//! makes of [`crate::scene::path_kind`]): `design` touches no file itself.

use std::path::{Path, PathBuf};

use serde_json::Value;

use super::chess;
use crate::scene::PathKind;

/// How the parser asks what a mesh path names: [`crate::scene::path_kind`], or a stand-in
/// in tests.
pub type Look<'a> = &'a dyn Fn(&Path) -> std::io::Result<PathKind>;

/// Density of an object when the list gives none (kg/m^3): hard maple, the wood of
/// Caroline Pratt's unit blocks. Chess pieces default to boxwood ([`chess::BOXWOOD`]).
pub const DEFAULT_DENSITY: f64 = 705.0;

/// The most objects a list may ask for.
pub const MAX_OBJECTS: usize = 64;

/// One object's shape.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    Sphere {
        radius: f64,
    },
    Box {
        size: [f64; 3],
    },
    /// An OBJ file, scaled.
    Mesh {
        obj: PathBuf,
        scale: f64,
    },
    /// A piece of the built-in chess set.
    Chess {
        piece: String,
    },
}

/// One object of the box.
#[derive(Clone, Debug, PartialEq)]
pub struct Item {
    pub kind: Kind,
    /// kg/m^3.
    pub density: f64,
}

/// The kind of object whose count the design chooses.
#[derive(Clone, Debug, PartialEq)]
pub enum AutoKind {
    /// Spheres; of this radius, or each of the radius its part of the picture needs.
    Sphere {
        radius: Option<f64>,
    },
    Box {
        size: [f64; 3],
    },
    Mesh {
        obj: PathBuf,
        scale: f64,
    },
    /// Pieces of one side of the chess set.
    Chess,
}

/// An `auto:` item.
#[derive(Clone, Debug, PartialEq)]
pub struct Auto {
    pub kind: AutoKind,
    pub density: f64,
    /// The most the design may add of it (`*N`); `None`: as many as pay.
    pub limit: Option<usize>,
}

/// An `auto:` item as the user's list names it.
impl std::fmt::Display for Auto {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.kind {
            AutoKind::Sphere { radius: None } => write!(f, "auto:sphere")?,
            AutoKind::Sphere { radius: Some(r) } => write!(f, "auto:sphere:{r}")?,
            AutoKind::Box { size } => write!(f, "auto:box:{}x{}x{}", size[0], size[1], size[2])?,
            AutoKind::Mesh { obj, scale } if *scale != 1.0 => {
                write!(f, "auto:mesh:{}@{scale}", obj.display())?
            }
            AutoKind::Mesh { obj, .. } => write!(f, "auto:mesh:{}", obj.display())?,
            AutoKind::Chess => write!(f, "auto:chess")?,
        }
        match self.limit {
            Some(n) => write!(f, "*{n}"),
            None => Ok(()),
        }
    }
}

/// A parsed list: the objects given, and the kinds whose counts are chosen.
#[derive(Clone, Debug, PartialEq)]
pub struct Inventory {
    pub items: Vec<Item>,
    pub autos: Vec<Auto>,
}

/// Why a list cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum InventoryError {
    /// The list is empty.
    #[error("the object list is empty (e.g. `box:0.14x0.07x0.035*6,sphere:0.1`)")]
    Empty,
    /// An item of a non-empty list is empty: two commas in a row, or one at an end.
    #[error("object list item {index} is empty (two commas in a row, or a comma at an end): remove the comma or put an object there")]
    EmptyItem { index: usize },
    /// An item names no known kind.
    #[error("object list item {index} `{item}`: unknown kind `{kind}` (sphere:R, box:XxYxZ, mesh:FILE.obj[@SCALE], chess:PIECE, chess, auto:...)")]
    Kind {
        index: usize,
        item: String,
        kind: String,
    },
    /// An item's numbers are malformed or out of range.
    #[error("object list item {index} `{item}`: {reason}")]
    Item {
        index: usize,
        item: String,
        reason: String,
    },
    /// A JSON object list is malformed, or has a key it does not know (at the top level
    /// or in an entry).
    #[error("{field}: {reason}")]
    Json { field: String, reason: String },
    /// More objects than [`MAX_OBJECTS`].
    #[error("the object list asks for {count} objects; at most {MAX_OBJECTS}")]
    TooMany { count: usize },
}

/// A count: given, or chosen by the design up to a limit.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Count {
    Fixed(usize),
    Auto(Option<usize>),
}

/// One entry before validation, as either syntax gives it.
#[derive(Default)]
struct Spec {
    kind: String,
    radius: Option<f64>,
    size: Option<[f64; 3]>,
    obj: Option<PathBuf>,
    /// The folder a JSON list's mesh paths are relative to (`None` on the command
    /// line, where they are relative to the current folder).
    obj_base: Option<PathBuf>,
    scale: Option<f64>,
    piece: Option<String>,
    auto: bool,
    count: Option<usize>,
    density: Option<f64>,
}

/// Why one number or file of an item is refused (the reason of an
/// [`InventoryError::Item`] or [`InventoryError::Json`]).
#[derive(Debug, thiserror::Error)]
enum Fault {
    /// A size or scale that is not in (0, 1000].
    #[error("{what} must be positive and at most 1000, got {got}")]
    NotPositive { what: String, got: String },
    /// A mesh path that names a folder.
    #[error("{} is a folder, not an OBJ file{relative_to}", .path.display())]
    Folder {
        path: PathBuf,
        relative_to: &'static str,
    },
    /// A mesh path that cannot be looked at (missing, or not readable).
    #[error("cannot read the OBJ file {}: {source}{relative_to}", .path.display())]
    Unreadable {
        path: PathBuf,
        source: std::io::Error,
        relative_to: &'static str,
    },
}

/// Check a positive number of at most 1000 (m, or a scale).
fn positive(x: f64, what: &str) -> Result<f64, Fault> {
    if x.is_finite() && x > 0.0 && x <= 1e3 {
        Ok(x)
    } else {
        Err(Fault::NotPositive {
            what: what.to_string(),
            got: crate::scene::short(x),
        })
    }
}

/// A field at fault and why: `(field, reason)`.
type Refusal = (String, String);

/// The [`Refusal`] of `field` for `reason`.
fn refuse(field: &str, reason: impl ToString) -> Refusal {
    (field.to_string(), reason.to_string())
}

/// A number the kind needs: present, positive and at most 1000.
fn need(v: Option<f64>, field: &str, what: &str) -> Result<f64, Refusal> {
    let x = v.ok_or_else(|| refuse(field, format!("{what} is missing")))?;
    positive(x, what).map_err(|r| refuse(field, r))
}

/// A piece of the built-in chess set, by name.
fn chess_piece(p: &str) -> Result<String, Refusal> {
    if chess::obj(p).is_some() {
        Ok(p.to_string())
    } else {
        let names: Vec<&str> = chess::PIECES.iter().map(|p| p.0).collect();
        Err(refuse(
            "piece",
            format!("unknown chess piece `{p}` ({})", names.join(", ")),
        ))
    }
}

impl Spec {
    /// The density: given (positive, at most 100000 kg/m^3), or the kind's default.
    fn density(&self) -> Result<f64, Refusal> {
        match self.density {
            Some(d) if !(d.is_finite() && d > 0.0 && d <= 1e5) => Err(refuse(
                "density",
                format!(
                    "density must be positive and at most 100000 kg/m^3, got {}",
                    crate::scene::short(d)
                ),
            )),
            Some(d) => Ok(d),
            None if self.kind == "chess" => Ok(chess::BOXWOOD),
            None => Ok(DEFAULT_DENSITY),
        }
    }

    /// The count: chosen by the design for an `auto:` item, at most its `*N` if given
    /// (at least 1; `auto:chess` takes a side's numbers), else given (at least 1) or 1.
    fn count(&self) -> Result<Count, Refusal> {
        if self.auto {
            return match self.count {
                Some(_) if self.kind == "chess" => Err(refuse(
                    "count",
                    "auto:chess adds at most a side's pieces of each kind; drop *N",
                )),
                Some(0) => Err(refuse(
                    "count",
                    "the most an auto: item adds must be at least 1",
                )),
                limit => Ok(Count::Auto(limit)),
            };
        }
        match self.count {
            Some(0) => Err(refuse("count", "count must be at least 1")),
            Some(n) => Ok(Count::Fixed(n)),
            None => Ok(Count::Fixed(1)),
        }
    }

    /// The scale of a mesh: given (positive, at most 1000), or 1.
    fn scale(&self) -> Result<f64, Refusal> {
        match self.scale {
            Some(s) => positive(s, "scale").map_err(|r| refuse("scale", r)),
            None => Ok(1.0),
        }
    }

    /// The OBJ file of a mesh, checked to be there ([`mesh_file`]).
    fn mesh(&self, look: Look) -> Result<PathBuf, Refusal> {
        match &self.obj {
            Some(p) if !p.as_os_str().is_empty() => {
                mesh_file(p, self.obj_base.as_deref(), look).map_err(|r| refuse("obj", r))?;
                Ok(p.clone())
            }
            _ => Err(refuse("obj", "mesh needs an OBJ file")),
        }
    }

    /// The size of a box (m), every side positive and at most 1000.
    fn size(&self) -> Result<[f64; 3], Refusal> {
        let s = self
            .size
            .ok_or_else(|| refuse("size", "box size must be XxYxZ in metres"))?;
        let mut out = [0.0; 3];
        for (o, x) in out.iter_mut().zip(s) {
            *o = positive(x, "box size").map_err(|r| refuse("size", r))?;
        }
        Ok(out)
    }

    /// The kind of an `auto:` item.
    fn auto_kind(&self, scale: f64, look: Look) -> Result<AutoKind, Refusal> {
        Ok(match self.kind.as_str() {
            "sphere" => AutoKind::Sphere {
                radius: match self.radius {
                    Some(r) => Some(positive(r, "radius").map_err(|e| refuse("radius", e))?),
                    None => None,
                },
            },
            "box" => AutoKind::Box { size: self.size()? },
            "mesh" => AutoKind::Mesh {
                obj: self.mesh(look)?,
                scale,
            },
            "chess" => {
                if self.piece.is_some() {
                    return Err(refuse(
                        "piece",
                        "auto:chess chooses the pieces too; give no piece",
                    ));
                }
                AutoKind::Chess
            }
            other => return Err(refuse("kind", format!("unknown kind `{other}`"))),
        })
    }

    /// The objects one of a counted item stands for: one, or the 16 pieces of a side of
    /// the chess set for `chess` without a piece.
    fn kinds(&self, scale: f64, look: Look) -> Result<Vec<Kind>, Refusal> {
        Ok(match self.kind.as_str() {
            "sphere" => vec![Kind::Sphere {
                radius: need(self.radius, "radius", "radius")?,
            }],
            "box" => vec![Kind::Box { size: self.size()? }],
            "mesh" => vec![Kind::Mesh {
                obj: self.mesh(look)?,
                scale,
            }],
            "chess" => match &self.piece {
                Some(p) => vec![Kind::Chess {
                    piece: chess_piece(p)?,
                }],
                None => chess::PIECES
                    .iter()
                    .flat_map(|(p, k)| {
                        std::iter::repeat_n(
                            Kind::Chess {
                                piece: p.to_string(),
                            },
                            *k,
                        )
                    })
                    .collect(),
            },
            other => return Err(refuse("kind", format!("unknown kind `{other}`"))),
        })
    }
}

/// Add `spec`'s objects to `inv`; `Err((field, reason))` names the field at fault.
fn add(spec: Spec, inv: &mut Inventory, look: Look) -> Result<(), Refusal> {
    let density = spec.density()?;
    let count = spec.count()?;
    let scale = spec.scale()?;
    let n = match count {
        Count::Fixed(n) => n,
        Count::Auto(limit) => {
            let kind = spec.auto_kind(scale, look)?;
            inv.autos.push(Auto {
                kind,
                density,
                limit,
            });
            return Ok(());
        }
    };
    let kinds = spec.kinds(scale, look)?;
    // Saturating: a JSON count near 2^64 must not wrap round to a small total.
    let total = inv
        .items
        .len()
        .saturating_add(n.saturating_mul(kinds.len()));
    if total > MAX_OBJECTS {
        return Err(refuse("count", InventoryError::TooMany { count: total }));
    }
    for _ in 0..n {
        inv.items.extend(kinds.iter().map(|k| Item {
            kind: k.clone(),
            density,
        }));
    }
    Ok(())
}

/// Check that a mesh's OBJ file is there, at `path` as the list gives it (joined to
/// `base`, a JSON list's folder): the scene that `bsa new` writes elsewhere must not
/// find another file of that name relative to its own folder. The reason names the
/// path and what it is relative to. The file's contents are checked when it is loaded.
fn mesh_file(path: &Path, base: Option<&Path>, look: Look) -> Result<(), Fault> {
    let relative_to = match base {
        Some(b) if path.is_relative() || path.starts_with(b) => {
            " (a JSON list's mesh paths are relative to the list's folder)"
        }
        Some(_) => "",
        None if path.is_relative() => " (mesh paths are relative to the current folder)",
        None => "",
    };
    match look(path) {
        Ok(PathKind::Folder) => Err(Fault::Folder {
            path: path.to_path_buf(),
            relative_to,
        }),
        Ok(PathKind::File) => Ok(()),
        Err(source) => Err(Fault::Unreadable {
            path: path.to_path_buf(),
            source,
            relative_to,
        }),
    }
}

/// The reason a count that is not a `usize` is refused: a whole number beyond the
/// largest list is too large, not malformed.
fn bad_count(n: &str) -> String {
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let n = n.trim();
    match n.strip_prefix('-') {
        Some(d) if digits(d) => format!("count must be at least 1, got {n}"),
        _ if digits(n.strip_prefix('+').unwrap_or(n)) => {
            format!("count {n} is more than the {MAX_OBJECTS} objects a list may hold")
        }
        _ => format!("count `{n}` is not a whole number"),
    }
}

/// Parse a comma-separated object list; `look` tells what a mesh path names.
pub fn parse(list: &str, look: Look) -> Result<Inventory, InventoryError> {
    let mut inv = Inventory {
        items: Vec::new(),
        autos: Vec::new(),
    };
    if list.trim().is_empty() {
        return Err(InventoryError::Empty);
    }
    for (k, raw) in list.split(',').map(str::trim).enumerate() {
        let index = k + 1;
        // An empty item is most likely a slip (an object deleted from the middle of
        // the list, or left out): reading the list without it could design a scene
        // with fewer objects than the user meant.
        if raw.is_empty() {
            return Err(InventoryError::EmptyItem { index });
        }
        let bad = |reason: String| InventoryError::Item {
            index,
            item: raw.to_string(),
            reason,
        };
        let number = |s: &str, what: &str| -> Result<f64, InventoryError> {
            s.trim()
                .parse::<f64>()
                .map_err(|_| bad(format!("{what} `{s}` is not a number")))
        };
        // [auto:]kind[:spec][*N][/DENSITY]: a trailing `/number` is the density (a mesh
        // path may hold slashes of its own).
        let (body, density) = match raw.rsplit_once('/') {
            Some((b, d)) if d.trim().parse::<f64>().is_ok() => (b, Some(number(d, "density")?)),
            _ => (raw, None),
        };
        let (spec_text, count) = match body.rsplit_once('*') {
            Some((s, n)) => {
                let n: usize = n.trim().parse().map_err(|_| bad(bad_count(n)))?;
                (s, Some(n))
            }
            None => (body, None),
        };
        let (auto, spec_text) = match spec_text.strip_prefix("auto:") {
            Some(rest) => (true, rest),
            None => (false, spec_text),
        };
        let (kind, arg) = match spec_text.split_once(':') {
            Some((k, a)) => (k.trim(), Some(a)),
            None => (spec_text.trim(), None),
        };
        let mut spec = Spec {
            kind: kind.to_string(),
            auto,
            count,
            density,
            ..Spec::default()
        };
        match (kind, arg) {
            ("sphere", Some(a)) => spec.radius = Some(number(a, "radius")?),
            ("sphere", None) if auto => {}
            ("box", Some(a)) => {
                let parts: Vec<&str> = a.split('x').collect();
                if parts.len() != 3 {
                    return Err(bad(format!("box size `{a}` must be XxYxZ in metres")));
                }
                spec.size = Some([
                    number(parts[0], "box size")?,
                    number(parts[1], "box size")?,
                    number(parts[2], "box size")?,
                ]);
            }
            ("mesh", Some(a)) => {
                let (file, scale) = match a.rsplit_once('@') {
                    Some((f, s)) => (f, Some(number(s, "scale")?)),
                    None => (a, None),
                };
                spec.obj = Some(PathBuf::from(file.trim()));
                spec.scale = scale;
            }
            ("chess", a) => spec.piece = a.map(|p| p.trim().to_string()),
            ("sphere" | "box" | "mesh", None) => {
                return Err(bad("expected kind:size, e.g. sphere:0.1".into()))
            }
            (other, _) => {
                return Err(InventoryError::Kind {
                    index,
                    item: raw.to_string(),
                    kind: other.to_string(),
                })
            }
        }
        add(spec, &mut inv, look).map_err(|(_, reason)| bad(reason))?;
    }
    if inv.items.is_empty() && inv.autos.is_empty() {
        return Err(InventoryError::Empty);
    }
    Ok(inv)
}

/// Parse a JSON object list: an array (or `{"objects": [...]}`) of entries
/// `{"kind": "sphere" | "box" | "mesh" | "chess", "radius": R, "size": [X, Y, Z],
/// "obj": FILE, "scale": S, "piece": NAME, "count": N | "auto", "at_most": N (the most
/// an "auto" entry adds), "density": D}` with the
/// fields of their kind. Mesh paths are relative to `base` (the file's folder); `look`
/// tells what one names.
pub fn parse_json(text: &str, base: &Path, look: Look) -> Result<Inventory, InventoryError> {
    let v: Value = serde_json::from_str(text)
        .map_err(|e| json("objects".into(), format!("not valid JSON: {e}")))?;
    let list = json_entries(&v)?;
    let mut inv = Inventory {
        items: Vec::new(),
        autos: Vec::new(),
    };
    for (i, e) in list.iter().enumerate() {
        let spec = json_spec(i, e, base)?;
        let at = |f: &str| format!("objects[{i}].{f}");
        add(spec, &mut inv, look).map_err(|(f, r)| json(at(&f), r))?;
    }
    if inv.items.is_empty() && inv.autos.is_empty() {
        return Err(InventoryError::Empty);
    }
    Ok(inv)
}

/// The [`InventoryError::Json`] of `field` for `reason`.
fn json(field: String, reason: String) -> InventoryError {
    InventoryError::Json { field, reason }
}

/// The entries of a JSON object list: the array, or the array of `{"objects": [...]}`
/// and nothing else.
fn json_entries(v: &Value) -> Result<Vec<Value>, InventoryError> {
    match v {
        Value::Array(a) => Ok(a.clone()),
        Value::Object(o) => {
            // As in an entry, a key the list does not know is refused rather than
            // ignored: it is a misspelling or a setting that would have no effect.
            if let Some(key) = o.keys().find(|k| k.as_str() != "objects") {
                return Err(json(
                    key.clone(),
                    "unknown key (the file holds an array, or {\"objects\": [...]} and nothing else)"
                        .into(),
                ));
            }
            match o.get("objects") {
                Some(Value::Array(a)) => Ok(a.clone()),
                _ => Err(json(
                    "objects".into(),
                    "expected an array of objects, or {\"objects\": [...]}".into(),
                )),
            }
        }
        _ => Err(json(
            "objects".into(),
            "expected an array of objects".into(),
        )),
    }
}

/// Entry `i` of a JSON object list as a [`Spec`], its mesh path joined to `base`; the
/// error names the entry's field (`objects[i].size`).
fn json_spec(i: usize, e: &Value, base: &Path) -> Result<Spec, InventoryError> {
    let at = |f: &str| format!("objects[{i}].{f}");
    let Value::Object(o) = e else {
        return Err(json(
            format!("objects[{i}]"),
            "expected an object such as {\"kind\": \"sphere\", \"radius\": 0.1}".into(),
        ));
    };
    let num = |f: &str| -> Result<Option<f64>, InventoryError> {
        match o.get(f) {
            None => Ok(None),
            Some(x) => x
                .as_f64()
                .map(Some)
                .ok_or_else(|| json(at(f), format!("expected a number, got {x}"))),
        }
    };
    let text_of = |f: &str| -> Result<Option<String>, InventoryError> {
        match o.get(f) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.clone())),
            Some(x) => Err(json(at(f), format!("expected a string, got {x}"))),
        }
    };
    for key in o.keys() {
        if ![
            "kind", "radius", "size", "obj", "scale", "piece", "count", "at_most", "density",
        ]
        .contains(&key.as_str())
        {
            return Err(json(at(key), "unknown field".into()));
        }
    }
    let kind = text_of("kind")?
        .ok_or_else(|| json(at("kind"), "missing (sphere, box, mesh or chess)".into()))?;
    let size = match o.get("size") {
        None => None,
        Some(Value::Array(a)) if a.len() == 3 && a.iter().all(Value::is_number) => {
            Some([0, 1, 2].map(|k| a[k].as_f64().expect("checked")))
        }
        Some(x) => {
            return Err(json(
                at("size"),
                format!("expected [X, Y, Z] in metres, got {x}"),
            ))
        }
    };
    let (auto, mut count) = json_count(o.get("count")).map_err(|r| json(at("count"), r))?;
    if let Some(limit) = o.get("at_most") {
        if !auto {
            return Err(json(
                at("at_most"),
                "only an entry with \"count\": \"auto\" takes at_most".into(),
            ));
        }
        count = Some(
            limit
                .as_u64()
                .map(|n| usize::try_from(n).unwrap_or(usize::MAX))
                .ok_or_else(|| {
                    json(
                        at("at_most"),
                        format!("expected a whole number, got {limit}"),
                    )
                })?,
        );
    }
    Ok(Spec {
        kind,
        radius: num("radius")?,
        size,
        obj: text_of("obj")?.map(|p| base.join(p)),
        obj_base: Some(base.to_path_buf()),
        scale: num("scale")?,
        piece: text_of("piece")?,
        auto,
        count,
        density: num("density")?,
    })
}

/// An entry's `count`: `(auto, count)` for none, `"auto"` or a whole number; the
/// reason a value is refused.
fn json_count(count: Option<&Value>) -> Result<(bool, Option<usize>), String> {
    match count {
        None => Ok((false, None)),
        Some(Value::String(s)) if s == "auto" => Ok((true, None)),
        Some(x) => match (x.as_u64(), x.as_f64()) {
            (Some(n), _) => Ok((false, Some(usize::try_from(n).unwrap_or(usize::MAX)))),
            // A whole number beyond u64 (read as a float) is too large, not
            // malformed; a negative one is below the least count.
            (None, Some(f)) if f.fract() == 0.0 && f > 0.0 => Err(format!(
                "count {f} is more than the {MAX_OBJECTS} objects a list may hold"
            )),
            (None, Some(f)) if f.fract() == 0.0 => {
                Err(format!("count must be at least 1, got {x}"))
            }
            _ => Err(format!("expected a whole number or \"auto\", got {x}")),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The file system as the command line looks at it.
    const LOOK: Look = &crate::scene::path_kind;

    #[test]
    fn counts_densities_and_scales_are_read() {
        let inv = parse(
            "box:0.14x0.07x0.035*2/600, sphere:0.1, mesh:scenes/thinker/pieces/pawn.obj@2*3",
            LOOK,
        )
        .unwrap();
        let items = inv.items;
        assert_eq!(items.len(), 6);
        assert_eq!(
            items[0],
            Item {
                kind: Kind::Box {
                    size: [0.14, 0.07, 0.035]
                },
                density: 600.0
            }
        );
        assert_eq!(items[2].kind, Kind::Sphere { radius: 0.1 });
        assert_eq!(items[2].density, DEFAULT_DENSITY);
        assert_eq!(
            items[5].kind,
            Kind::Mesh {
                obj: "scenes/thinker/pieces/pawn.obj".into(),
                scale: 2.0
            }
        );
        assert!(inv.autos.is_empty());
    }

    #[test]
    fn chess_and_auto_items_are_read() {
        let inv = parse("chess", LOOK).unwrap();
        assert_eq!(inv.items.len(), 16);
        assert!(inv.items.iter().all(|i| i.density == chess::BOXWOOD));
        let pawns = inv
            .items
            .iter()
            .filter(|i| {
                i.kind
                    == Kind::Chess {
                        piece: "pawn".into(),
                    }
            })
            .count();
        assert_eq!(pawns, 8);
        let inv = parse("chess:king,auto:box:0.14x0.07x0.035/650", LOOK).unwrap();
        assert_eq!(inv.items.len(), 1);
        assert_eq!(
            inv.autos,
            [Auto {
                kind: AutoKind::Box {
                    size: [0.14, 0.07, 0.035]
                },
                density: 650.0,
                limit: None,
            }]
        );
        assert_eq!(
            parse("auto:sphere", LOOK).unwrap().autos[0].kind,
            AutoKind::Sphere { radius: None }
        );
        assert_eq!(
            parse("auto:sphere:0.2", LOOK).unwrap().autos[0].kind,
            AutoKind::Sphere { radius: Some(0.2) }
        );
        assert_eq!(
            parse("auto:chess", LOOK).unwrap().autos[0].kind,
            AutoKind::Chess
        );
        // A box of blocks of three sizes, the smallest at most four.
        let inv = parse(
            "auto:box:0.28x0.07x0.035,auto:box:0.14x0.07x0.035,auto:box:0.07x0.07x0.035*4",
            LOOK,
        )
        .unwrap();
        let limits: Vec<Option<usize>> = inv.autos.iter().map(|a| a.limit).collect();
        assert_eq!(limits, [None, None, Some(4)]);
        assert_eq!(inv.autos[2].to_string(), "auto:box:0.07x0.07x0.035*4");
    }

    #[test]
    fn a_json_list_reads_like_the_command_line() {
        let text = r#"{"objects": [
            {"kind": "box", "size": [0.14, 0.07, 0.035], "count": 2, "density": 600},
            {"kind": "mesh", "obj": "pawn.obj", "scale": 2},
            {"kind": "sphere", "count": "auto", "at_most": 5}]}"#;
        let inv = parse_json(text, Path::new("scenes/thinker/pieces"), LOOK).unwrap();
        assert_eq!(inv.items.len(), 3);
        assert_eq!(
            inv.items[0],
            parse("box:0.14x0.07x0.035/600", LOOK).unwrap().items[0]
        );
        assert_eq!(
            inv.items[2].kind,
            Kind::Mesh {
                obj: "scenes/thinker/pieces/pawn.obj".into(),
                scale: 2.0
            }
        );
        assert_eq!(
            inv.autos,
            [Auto {
                kind: AutoKind::Sphere { radius: None },
                density: DEFAULT_DENSITY,
                limit: Some(5)
            }]
        );
    }

    #[test]
    fn bad_items_are_named() {
        for (list, expect) in [
            ("", "empty"),
            ("cone:1", "unknown kind `cone`"),
            ("sphere:-1", "radius must be positive"),
            ("box:1x2", "XxYxZ"),
            ("sphere:0.1*0", "at least 1"),
            ("sphere:0.1*1000", "at most 64"),
            ("sphere:abc", "not a number"),
            ("chess:emperor", "unknown chess piece `emperor`"),
            ("auto:chess*3", "drop *N"),
            ("auto:box:0.1x0.1x0.1*0", "must be at least 1"),
            ("sphere", "expected kind:size"),
            ("sphere:0.1,,sphere:0.1", "item 2 is empty"),
            ("sphere:0.1,", "item 2 is empty"),
            (
                "sphere:0.1*1000000000000000000000000000000",
                "more than the 64 objects",
            ),
            ("sphere:0.1*-2", "at least 1, got -2"),
            ("sphere:0.1*2.5", "`2.5` is not a whole number"),
            (
                "mesh:no/such/file.obj",
                "cannot read the OBJ file no/such/file.obj",
            ),
            ("mesh:scenes", "scenes is a folder"),
        ] {
            let e = parse(list, LOOK).unwrap_err().to_string();
            assert!(e.contains(expect), "{list}: {e}");
        }
        for (text, expect) in [
            (
                "[{\"kind\": \"box\", \"size\": [1, 2]}]",
                "objects[0].size: expected [X, Y, Z]",
            ),
            (
                "[{\"kind\": \"sphere\"}]",
                "objects[0].radius: radius is missing",
            ),
            (
                "[{\"kind\": \"sphere\", \"radius\": 0.1, \"colour\": 1}]",
                "objects[0].colour: unknown field",
            ),
            ("[{\"radius\": 0.1}]", "objects[0].kind: missing"),
            (
                "[{\"kind\": \"box\", \"size\": [1, 1, 1], \"count\": \"many\"}]",
                "objects[0].count",
            ),
            (
                "[{\"kind\": \"sphere\", \"radius\": 0.1, \"at_most\": 2}]",
                "objects[0].at_most: only an entry with",
            ),
            ("{\"things\": []}", "things: unknown key"),
            ("{\"objects\": 1}", "objects: expected an array"),
            (
                "{\"objects\": [{\"kind\": \"sphere\", \"radius\": 0.1}], \"extra\": 1}",
                "extra: unknown key",
            ),
            (
                "[{\"kind\": \"sphere\", \"radius\": 0.1, \"count\": 99999999999999999999}]",
                "objects[0].count: count 100000000000000000000 is more than the 64",
            ),
            (
                "[{\"kind\": \"chess\", \"count\": 1152921504606846976}]",
                "at most 64",
            ),
            (
                "[{\"kind\": \"mesh\", \"obj\": \"nosuch.obj\"}]",
                "objects[0].obj: cannot read the OBJ file ./nosuch.obj",
            ),
            ("[1", "not valid JSON"),
        ] {
            let e = parse_json(text, Path::new("."), LOOK)
                .unwrap_err()
                .to_string();
            assert!(e.contains(expect), "{text}: {e}");
        }
    }
}
