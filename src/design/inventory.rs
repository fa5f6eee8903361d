//! A box of objects, as a user lists them: `sphere:R`, `box:XxYxZ` or
//! `mesh:FILE.obj[@SCALE]`, each with an optional `*N` count and `/DENSITY`, separated by
//! commas (metres and kg/m^3). [`parse`] turns such a list into [`Item`]s, or says which
//! item is wrong and why.

use std::path::PathBuf;

/// Density of an object when the list gives none (kg/m^3): hard maple, the wood of
/// Caroline Pratt's unit blocks.
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
}

/// One object of the box.
#[derive(Clone, Debug, PartialEq)]
pub struct Item {
    pub kind: Kind,
    /// kg/m^3.
    pub density: f64,
}

/// Why a list cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum InventoryError {
    /// The list is empty.
    #[error("the object list is empty (e.g. `box:0.14x0.07x0.035*6,sphere:0.1`)")]
    Empty,
    /// An item names no known kind.
    #[error("object list item {index} `{item}`: unknown kind `{kind}` (sphere:R, box:XxYxZ, mesh:FILE.obj[@SCALE])")]
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
    /// More objects than [`MAX_OBJECTS`].
    #[error("the object list asks for {count} objects; at most {MAX_OBJECTS}")]
    TooMany { count: usize },
}

/// Parse a comma-separated object list.
pub fn parse(list: &str) -> Result<Vec<Item>, InventoryError> {
    let mut items = Vec::new();
    for (k, raw) in list.split(',').map(str::trim).enumerate() {
        if raw.is_empty() {
            continue;
        }
        let index = k + 1;
        let bad = |reason: String| InventoryError::Item {
            index,
            item: raw.to_string(),
            reason,
        };
        let number = |s: &str, what: &str| -> Result<f64, InventoryError> {
            let x: f64 = s
                .trim()
                .parse()
                .map_err(|_| bad(format!("{what} `{s}` is not a number")))?;
            if x.is_finite() && x > 0.0 && x <= 1e3 {
                Ok(x)
            } else {
                Err(bad(format!(
                    "{what} must be positive and at most 1000, got {s}"
                )))
            }
        };
        // kind:spec[*N][/DENSITY]: a trailing `/number` is the density (a mesh path may
        // hold slashes of its own).
        let (body, density) = match raw.rsplit_once('/') {
            Some((b, d)) if d.trim().parse::<f64>().is_ok() => {
                let x: f64 = d.trim().parse().expect("checked");
                if !(x.is_finite() && x > 0.0 && x <= 1e5) {
                    return Err(bad(format!(
                        "density must be positive and at most 100000 kg/m^3, got {d}"
                    )));
                }
                (b, x)
            }
            _ => (raw, DEFAULT_DENSITY),
        };
        let (spec, count) = match body.rsplit_once('*') {
            Some((s, n)) => {
                let n: usize = n
                    .trim()
                    .parse()
                    .map_err(|_| bad(format!("count `{n}` is not a whole number")))?;
                if n == 0 {
                    return Err(bad("count must be at least 1".into()));
                }
                (s, n)
            }
            None => (body, 1),
        };
        let (kind, arg) = spec
            .split_once(':')
            .ok_or_else(|| bad("expected kind:size, e.g. sphere:0.1".into()))?;
        let kind = match kind.trim() {
            "sphere" => Kind::Sphere {
                radius: number(arg, "radius")?,
            },
            "box" => {
                let parts: Vec<&str> = arg.split('x').collect();
                if parts.len() != 3 {
                    return Err(bad(format!("box size `{arg}` must be XxYxZ in metres")));
                }
                Kind::Box {
                    size: [
                        number(parts[0], "box size")?,
                        number(parts[1], "box size")?,
                        number(parts[2], "box size")?,
                    ],
                }
            }
            "mesh" => {
                let (file, scale) = match arg.rsplit_once('@') {
                    Some((f, s)) => (f, number(s, "scale")?),
                    None => (arg, 1.0),
                };
                if file.trim().is_empty() {
                    return Err(bad("mesh needs an OBJ file".into()));
                }
                Kind::Mesh {
                    obj: PathBuf::from(file.trim()),
                    scale,
                }
            }
            other => {
                return Err(InventoryError::Kind {
                    index,
                    item: raw.to_string(),
                    kind: other.to_string(),
                })
            }
        };
        if items.len() + count > MAX_OBJECTS {
            return Err(InventoryError::TooMany {
                count: items.len() + count,
            });
        }
        items.extend(std::iter::repeat_n(Item { kind, density }, count));
    }
    if items.is_empty() {
        return Err(InventoryError::Empty);
    }
    Ok(items)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_densities_and_scales_are_read() {
        let items =
            parse("box:0.14x0.07x0.035*2/600, sphere:0.1, mesh:pieces/pawn.obj@2*3").unwrap();
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
                obj: "pieces/pawn.obj".into(),
                scale: 2.0
            }
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
        ] {
            let e = parse(list).unwrap_err().to_string();
            assert!(e.contains(expect), "{list}: {e}");
        }
    }
}
