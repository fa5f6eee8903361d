//! What `bsa new` tells the user when the box of objects cannot draw the picture, which
//! no solve mends ([`note`]): parts of the picture narrower than any of the objects'
//! shadows ([`thin_parts`], [`ThinParts`]) and a target the objects leave bare; and the
//! wider picture it takes itself for an automatic inventory ([`auto_width`]).

use super::cover::{Frame, LEAST_BALL_M};
use super::picture::Picture;
use super::{AutoObject, AutoStop, Request, BARE_SHARE};

/// The parts of a picture narrower than any shadow a box of objects casts
/// ([`thin_parts`]): no object draws them without spilling over their sides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinParts {
    /// Share of the target (0 to 1) narrower than the narrowest shadow.
    pub share: f64,
    /// The narrowest shadow's width (m): the narrowest object's least width at the
    /// least magnification the design uses (higher flights cast wider shadows).
    pub least_width: f64,
    /// The picture's width (m) at which no more than [`BARE_SHARE`] of the target is
    /// narrower than that shadow; infinite where even the picture's widest parts are.
    pub width_needed: f64,
}

/// How much of `picture` is narrower than the narrowest shadow that the objects of
/// `request` cast (balls of `auto:sphere` as small as [`LEAST_BALL_M`]), and at what
/// picture width that share falls to [`BARE_SHARE`]. `None` when the request has no
/// objects.
pub fn thin_parts(picture: &Picture, frame: &Frame, request: &Request) -> Option<ThinParts> {
    let px = frame.metres_per_px;
    // The narrowest object's least side, a ball of `auto:sphere` as small as it comes.
    let widths = request.auto.iter().map(|(kind, _)| match kind {
        AutoObject::Given(o) => o.shape.least_width(),
        AutoObject::Sphere { .. } => 2.0 * LEAST_BALL_M,
    });
    let least = request
        .fixed
        .iter()
        .map(|o| o.shape.least_width())
        .chain(widths)
        .fold(f64::INFINITY, f64::min)
        * frame.m_lo;
    if !least.is_finite() {
        return None;
    }
    let d = picture.distance();
    let need = least / px / 2.0;
    let share = picture.thin_share(&d, need);
    // The largest disc radius (pixels) that leaves at most BARE_SHARE thin, bisected:
    // the share grows with the radius, and no on pixel is thinner than a pixel.
    let (mut lo, mut hi) = (0.5, need);
    if share > BARE_SHARE {
        for _ in 0..12 {
            let mid = 0.5 * (lo + hi);
            if picture.thin_share(&d, mid) <= BARE_SHARE {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    } else {
        lo = need;
    }
    let width_m = px * picture.width as f64;
    Some(ThinParts {
        share,
        least_width: least,
        width_needed: if lo > 0.5 {
            width_m * need / lo
        } else {
            f64::INFINITY
        },
    })
}

/// The most an automatic inventory widens the picture ([`auto_width`]): twice the
/// width is four times the area, and the count grows with the area up to the cap of
/// [`super::AUTO_CAP`] balls (half as many other objects); beyond, the note tells the width
/// and leaves it to the user.
const MOST_WIDENING: f64 = 2.0;

/// A width (m) up to the centimetre above, so that the width said is enough.
fn up_to_cm(width: f64) -> f64 {
    (100.0 * width).ceil() / 100.0
}

/// The picture width (m) that `bsa new` takes for a `request` with `auto:` items when
/// the user sets none, the picture now `width` wide (`frame` its design frame): where more
/// than [`BARE_SHARE`] of `picture` is narrower than the narrowest shadow the objects
/// cast, the width at which all but that share is as wide (up to the centimetre, at most
/// [`MOST_WIDENING`] times `width`), with the thin parts found at `width`. `None` where
/// the picture is wide enough, the request has no `auto:` item (its count is the user's)
/// or no width within reach helps.
pub fn auto_width(
    picture: &Picture,
    frame: &Frame,
    request: &Request,
    width: f64,
) -> Option<(f64, ThinParts)> {
    if request.auto.is_empty() {
        return None;
    }
    let thin = thin_parts(picture, frame, request)?;
    let wider = up_to_cm(thin.width_needed);
    (thin.share > BARE_SHARE && wider > width && wider <= MOST_WIDENING * width)
        .then_some((wider, thin))
}

/// With more than [`BARE_SHARE`] of the target bare at the start, a final (or
/// start) IoU below this says the objects are too few or of the wrong proportions for
/// the picture.
const SHORT_IOU: f64 = 0.9;

/// A note for the user when the box of objects cannot draw the picture, which no solve
/// mends: much of the picture is narrower than any of the objects' shadows (`thin`, read
/// only when the IoU is short), or most of what the start guess misses is target no
/// object's shadow reaches. `None` when the objects suffice. For thin parts, a wider
/// picture helps, or narrower objects; for bare ones, what helps depends on why an
/// automatic count stopped (`auto`): at the cap, more objects than it adds; where one
/// more gains too little, a size that fits the parts left bare.
pub fn note(
    missed: f64,
    iou: f64,
    auto: Option<AutoStop>,
    thin: &dyn Fn() -> Option<ThinParts>,
) -> Option<String> {
    if iou >= SHORT_IOU {
        return None;
    }
    if let Some(t) = thin().filter(|t| t.share > BARE_SHARE) {
        let wider = if t.width_needed.is_finite() {
            format!(
                "at --width {:.2} or more, all but {:.0} % of it is as wide; or give narrower objects",
                up_to_cm(t.width_needed),
                100.0 * BARE_SHARE
            )
        } else {
            "give narrower objects".to_string()
        };
        return Some(format!(
            "{:.0} % of the picture is narrower than the narrowest shadow the objects cast ({:.1} cm), so their shadows spill over its sides or leave it bare (the design reaches IoU {iou:.3}); {wider}",
            100.0 * t.share,
            100.0 * t.least_width
        ));
    }
    if missed <= BARE_SHARE {
        return None;
    }
    let advice = match auto {
        None => "more objects, or objects shaped more like its parts (auto:box:XxYxZ, auto:sphere or auto:chess lets bsa new choose how many, and several auto:box items which sizes)".to_string(),
        Some(AutoStop::Cap(n)) => format!("more objects than auto: adds (it stops at its cap, here {n} objects): a count above it on the auto: item (such as auto:sphere*{}) raises the cap, each object adding to the solve's time", 2 * n),
        Some(_) => "objects of a size that fits its bare parts (another auto: item of a smaller size)".to_string(),
    };
    Some(format!(
        "the objects leave {:.0} % of the picture bare at the start, and the design reaches IoU {iou:.3}; the picture may need {advice}",
        100.0 * missed
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::tests::{block, body_on_legs};

    #[test]
    fn thin_parts_are_those_narrower_than_the_narrowest_shadow_and_a_wider_picture_widens_them() {
        // A body on legs 6 px wide, a fifth of the target.
        let (pic, frame) = body_on_legs();
        let blocks = |least: f64| Request {
            fixed: vec![block(0.14, 0.07, least)],
            auto: vec![(AutoObject::Given(block(0.07, 0.07, 0.07)), 3)],
        };
        // The narrowest shadow is 4 px across: the legs are as wide.
        let narrow = blocks(4.0 * frame.metres_per_px / frame.m_lo);
        let t = thin_parts(&pic, &frame, &narrow).unwrap();
        assert!(t.share < 0.02, "{t:?}");
        assert_eq!(t.width_needed, frame.metres_per_px * pic.width as f64);
        // 10 px across: the legs are thin, and at the width the note gives they are not.
        let wide = blocks(10.0 * frame.metres_per_px / frame.m_lo);
        let t = thin_parts(&pic, &frame, &wide).unwrap();
        assert!(t.share > BARE_SHARE, "{t:?}");
        let scale = t.width_needed / (frame.metres_per_px * pic.width as f64);
        assert!(scale > 1.0 && scale < 10.0 / 6.0 + 0.1, "{t:?}");
        let wider = Frame {
            metres_per_px: frame.metres_per_px * scale,
            ..frame
        };
        let at = thin_parts(&pic, &wider, &wide).unwrap();
        assert!(at.share <= BARE_SHARE, "{at:?}");
        // Balls may be as small as the least ball.
        let balls = Request {
            fixed: Vec::new(),
            auto: vec![(AutoObject::Sphere { density: 705.0 }, usize::MAX)],
        };
        let t = thin_parts(&pic, &frame, &balls).unwrap();
        assert_eq!(t.least_width, 2.0 * LEAST_BALL_M * frame.m_lo);
        let none = Request {
            fixed: Vec::new(),
            auto: Vec::new(),
        };
        assert_eq!(thin_parts(&pic, &frame, &none), None);
    }

    #[test]
    fn an_automatic_inventory_widens_the_picture_for_its_thin_parts_up_to_twice() {
        let (pic, frame) = body_on_legs();
        let width = frame.metres_per_px * pic.width as f64;
        let px = |n: f64| n * frame.metres_per_px / frame.m_lo;
        let auto = |least: f64| Request {
            fixed: Vec::new(),
            auto: vec![(AutoObject::Given(block(0.14, 0.07, least)), usize::MAX)],
        };
        // Legs 6 px wide against a shadow 10 px across: the width the note gives, to the
        // centimetre above.
        let (taken, thin) = auto_width(&pic, &frame, &auto(px(10.0)), width).unwrap();
        assert_eq!(thin, thin_parts(&pic, &frame, &auto(px(10.0))).unwrap());
        assert_eq!(taken, up_to_cm(thin.width_needed));
        assert!(
            taken > width && taken <= MOST_WIDENING * width,
            "{taken} of {width}"
        );
        // The user's own count keeps the user's picture; so does a shadow as narrow as
        // the legs, and one so wide that no picture within twice the width helps.
        let stated = Request {
            fixed: vec![block(0.14, 0.07, px(10.0))],
            auto: Vec::new(),
        };
        assert_eq!(auto_width(&pic, &frame, &stated, width), None);
        assert_eq!(auto_width(&pic, &frame, &auto(px(4.0)), width), None);
        let far = thin_parts(&pic, &frame, &auto(px(30.0))).unwrap();
        assert!(far.width_needed > MOST_WIDENING * width, "{far:?}");
        assert_eq!(auto_width(&pic, &frame, &auto(px(30.0)), width), None);
    }
}
