//! A box of objects, as a user lists them. [`parse`] reads the command-line list:
//! comma-separated items `sphere:R`, `box:XxYxZ`, `mesh:FILE.obj[@SCALE]`, `chess:PIECE`
//! (a piece of the built-in chess set) or `chess` (one side: 16 pieces), each with an
//! optional `*N` count and `/DENSITY` (metres, kg/m^3); and at most one item that lets
//! the design choose the count: `auto:sphere` (radii chosen too), `auto:sphere:R`,
//! `auto:box:XxYxZ`, `auto:mesh:FILE.obj[@SCALE]`, `auto:chess` (pieces of one side).
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
}

/// A parsed list: the objects given, and at most one kind whose count is chosen.
#[derive(Clone, Debug, PartialEq)]
pub struct Inventory {
    pub items: Vec<Item>,
    pub auto: Option<Auto>,
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
    /// More than one `auto:` item.
    #[error("at most one auto: item may choose its count (items {first} and {second} both do)")]
    TwoAutos { first: usize, second: usize },
}

/// A count: given, or chosen by the design.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Count {
    Fixed(usize),
    Auto,
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

/// Add `spec`'s objects to `inv`; `Err((field, reason))` names the field at fault.
fn add(
    spec: Spec,
    inv: &mut Inventory,
    auto_at: &mut Option<usize>,
    index: usize,
    look: Look,
) -> Result<(), (String, String)> {
    let bad = |field: &str, reason: String| (field.to_string(), reason);
    let fault = |field: &str, reason: Fault| (field.to_string(), reason.to_string());
    let density = match spec.density {
        Some(d) if !(d.is_finite() && d > 0.0 && d <= 1e5) => {
            return Err(bad(
                "density",
                format!(
                    "density must be positive and at most 100000 kg/m^3, got {}",
                    crate::scene::short(d)
                ),
            ))
        }
        Some(d) => d,
        None if spec.kind == "chess" => chess::BOXWOOD,
        None => DEFAULT_DENSITY,
    };
    let count = if spec.auto {
        if spec.count.is_some() {
            return Err(bad(
                "count",
                "an auto: item chooses its own count; drop *N".into(),
            ));
        }
        Count::Auto
    } else {
        match spec.count {
            Some(0) => return Err(bad("count", "count must be at least 1".into())),
            Some(n) => Count::Fixed(n),
            None => Count::Fixed(1),
        }
    };
    let need = |v: Option<f64>, field: &str, what: &str| -> Result<f64, (String, String)> {
        let x = v.ok_or_else(|| bad(field, format!("{what} is missing")))?;
        positive(x, what).map_err(|r| fault(field, r))
    };
    let scale = match spec.scale {
        Some(s) => positive(s, "scale").map_err(|r| fault("scale", r))?,
        None => 1.0,
    };
    let mesh = || -> Result<PathBuf, (String, String)> {
        match &spec.obj {
            Some(p) if !p.as_os_str().is_empty() => {
                mesh_file(p, spec.obj_base.as_deref(), look).map_err(|r| fault("obj", r))?;
                Ok(p.clone())
            }
            _ => Err(bad("obj", "mesh needs an OBJ file".into())),
        }
    };
    let size = || -> Result<[f64; 3], (String, String)> {
        let s = spec
            .size
            .ok_or_else(|| bad("size", "box size must be XxYxZ in metres".into()))?;
        let mut out = [0.0; 3];
        for (o, x) in out.iter_mut().zip(s) {
            *o = positive(x, "box size").map_err(|r| fault("size", r))?;
        }
        Ok(out)
    };
    let piece = |p: &str| -> Result<String, (String, String)> {
        if chess::obj(p).is_some() {
            Ok(p.to_string())
        } else {
            let names: Vec<&str> = chess::PIECES.iter().map(|p| p.0).collect();
            Err(bad(
                "piece",
                format!("unknown chess piece `{p}` ({})", names.join(", ")),
            ))
        }
    };
    if count == Count::Auto {
        if let Some(first) = *auto_at {
            return Err(bad(
                "auto",
                format!(
                    "{}",
                    InventoryError::TwoAutos {
                        first,
                        second: index
                    }
                ),
            ));
        }
        *auto_at = Some(index);
        let kind = match spec.kind.as_str() {
            "sphere" => AutoKind::Sphere {
                radius: match spec.radius {
                    Some(r) => Some(positive(r, "radius").map_err(|e| fault("radius", e))?),
                    None => None,
                },
            },
            "box" => AutoKind::Box { size: size()? },
            "mesh" => AutoKind::Mesh {
                obj: mesh()?,
                scale,
            },
            "chess" => {
                if spec.piece.is_some() {
                    return Err(bad(
                        "piece",
                        "auto:chess chooses the pieces too; give no piece".into(),
                    ));
                }
                AutoKind::Chess
            }
            other => return Err(bad("kind", format!("unknown kind `{other}`"))),
        };
        inv.auto = Some(Auto { kind, density });
        return Ok(());
    }
    let Count::Fixed(n) = count else {
        unreachable!()
    };
    let kinds: Vec<Kind> = match spec.kind.as_str() {
        "sphere" => vec![Kind::Sphere {
            radius: need(spec.radius, "radius", "radius")?,
        }],
        "box" => vec![Kind::Box { size: size()? }],
        "mesh" => vec![Kind::Mesh {
            obj: mesh()?,
            scale,
        }],
        "chess" => match &spec.piece {
            Some(p) => vec![Kind::Chess { piece: piece(p)? }],
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
        other => return Err(bad("kind", format!("unknown kind `{other}`"))),
    };
    // Saturating: a JSON count near 2^64 must not wrap round to a small total.
    let total = inv
        .items
        .len()
        .saturating_add(n.saturating_mul(kinds.len()));
    if total > MAX_OBJECTS {
        return Err(bad(
            "count",
            format!("{}", InventoryError::TooMany { count: total }),
        ));
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
        auto: None,
    };
    if list.trim().is_empty() {
        return Err(InventoryError::Empty);
    }
    let mut auto_at = None;
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
        add(spec, &mut inv, &mut auto_at, index, look).map_err(|(_, reason)| bad(reason))?;
    }
    if inv.items.is_empty() && inv.auto.is_none() {
        return Err(InventoryError::Empty);
    }
    Ok(inv)
}

/// Parse a JSON object list: an array (or `{"objects": [...]}`) of entries
/// `{"kind": "sphere" | "box" | "mesh" | "chess", "radius": R, "size": [X, Y, Z],
/// "obj": FILE, "scale": S, "piece": NAME, "count": N | "auto", "density": D}` with the
/// fields of their kind. Mesh paths are relative to `base` (the file's folder); `look`
/// tells what one names.
pub fn parse_json(text: &str, base: &Path, look: Look) -> Result<Inventory, InventoryError> {
    let json = |field: String, reason: String| InventoryError::Json { field, reason };
    let v: Value = serde_json::from_str(text)
        .map_err(|e| json("objects".into(), format!("not valid JSON: {e}")))?;
    let list = match &v {
        Value::Array(a) => a.clone(),
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
                Some(Value::Array(a)) => a.clone(),
                _ => {
                    return Err(json(
                        "objects".into(),
                        "expected an array of objects, or {\"objects\": [...]}".into(),
                    ))
                }
            }
        }
        _ => {
            return Err(json(
                "objects".into(),
                "expected an array of objects".into(),
            ))
        }
    };
    let mut inv = Inventory {
        items: Vec::new(),
        auto: None,
    };
    let mut auto_at = None;
    for (i, e) in list.iter().enumerate() {
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
                "kind", "radius", "size", "obj", "scale", "piece", "count", "density",
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
        let (auto, count) = match o.get("count") {
            None => (false, None),
            Some(Value::String(s)) if s == "auto" => (true, None),
            Some(x) => match (x.as_u64(), x.as_f64()) {
                (Some(n), _) => (false, Some(usize::try_from(n).unwrap_or(usize::MAX))),
                // A whole number beyond u64 (read as a float) is too large, not
                // malformed; a negative one is below the least count.
                (None, Some(f)) if f.fract() == 0.0 && f > 0.0 => {
                    return Err(json(
                        at("count"),
                        format!("count {f} is more than the {MAX_OBJECTS} objects a list may hold"),
                    ))
                }
                (None, Some(f)) if f.fract() == 0.0 => {
                    return Err(json(
                        at("count"),
                        format!("count must be at least 1, got {x}"),
                    ))
                }
                _ => {
                    return Err(json(
                        at("count"),
                        format!("expected a whole number or \"auto\", got {x}"),
                    ))
                }
            },
        };
        let spec = Spec {
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
        };
        add(spec, &mut inv, &mut auto_at, i + 1, look).map_err(|(f, r)| json(at(&f), r))?;
    }
    if inv.items.is_empty() && inv.auto.is_none() {
        return Err(InventoryError::Empty);
    }
    Ok(inv)
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
        assert!(inv.auto.is_none());
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
            inv.auto,
            Some(Auto {
                kind: AutoKind::Box {
                    size: [0.14, 0.07, 0.035]
                },
                density: 650.0
            })
        );
        assert_eq!(
            parse("auto:sphere", LOOK).unwrap().auto.unwrap().kind,
            AutoKind::Sphere { radius: None }
        );
        assert_eq!(
            parse("auto:sphere:0.2", LOOK).unwrap().auto.unwrap().kind,
            AutoKind::Sphere { radius: Some(0.2) }
        );
        assert_eq!(
            parse("auto:chess", LOOK).unwrap().auto.unwrap().kind,
            AutoKind::Chess
        );
    }

    #[test]
    fn a_json_list_reads_like_the_command_line() {
        let text = r#"{"objects": [
            {"kind": "box", "size": [0.14, 0.07, 0.035], "count": 2, "density": 600},
            {"kind": "mesh", "obj": "pawn.obj", "scale": 2},
            {"kind": "sphere", "count": "auto"}]}"#;
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
        assert_eq!(inv.auto.unwrap().kind, AutoKind::Sphere { radius: None });
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
            ("auto:box:0.1x0.1x0.1*3", "drop *N"),
            ("auto:sphere,auto:chess", "at most one auto"),
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
