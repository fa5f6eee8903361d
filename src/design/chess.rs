//! The chess set `bsa new` knows by name (`chess:PIECE`, `chess`, `auto:chess`): one side
//! of the Staunton set of `docs/chess-pieces.md`, whose meshes are built into the binary
//! (the committed `scenes/thinker/pieces/*.obj`, made by `examples/chess_pieces.rs`) and
//! written beside a scene that uses them.

/// Density of a chess piece when the list gives none (kg/m^3): boxwood.
pub const BOXWOOD: f64 = 900.0;

/// The pieces, largest first, with how many one side has.
pub const PIECES: [(&str, usize); 6] = [
    ("king", 1),
    ("queen", 1),
    ("rook", 2),
    ("bishop", 2),
    ("knight", 2),
    ("pawn", 8),
];

/// The OBJ text of a piece, or `None` for an unknown name.
pub fn obj(piece: &str) -> Option<&'static str> {
    Some(match piece {
        "king" => include_str!("../../scenes/thinker/pieces/king.obj"),
        "queen" => include_str!("../../scenes/thinker/pieces/queen.obj"),
        "rook" => include_str!("../../scenes/thinker/pieces/rook.obj"),
        "bishop" => include_str!("../../scenes/thinker/pieces/bishop.obj"),
        "knight" => include_str!("../../scenes/thinker/pieces/knight.obj"),
        "pawn" => include_str!("../../scenes/thinker/pieces/pawn.obj"),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_piece_has_a_mesh_and_a_side_has_sixteen() {
        for (p, _) in PIECES {
            assert!(obj(p).is_some_and(|t| t.contains("\nf ")), "{p}");
        }
        assert!(obj("emperor").is_none());
        assert_eq!(PIECES.iter().map(|p| p.1).sum::<usize>(), 16);
    }
}
