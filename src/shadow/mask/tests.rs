use super::*;

/// Small deterministic generator (SplitMix64) so the tests need no dependencies.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A random mask of blobs and noise, with some empty rows at top and bottom.
fn random_mask(rng: &mut Rng, w: usize, h: usize, density: u64) -> Mask {
    let (top, bottom) = (rng.below(h / 3 + 1), h - rng.below(h / 3 + 1));
    Mask::from_fn(w, h, |_, y| {
        y >= top && y < bottom && rng.next() % 100 < density
    })
}

fn padding_is_zero(m: &Mask) -> bool {
    (0..m.height()).all(|j| m.row(j)[m.words_per_row() - 1] & !m.last_word_mask() == 0)
}

#[test]
fn fill_span_matches_per_bit_reference_across_word_boundaries() {
    let w = 200;
    let spans = [
        (0, 0),
        (0, 63),
        (63, 64),
        (1, 62),
        (60, 130),
        (64, 127),
        (64, 128),
        (5, 199),
        (0, 199),
        (127, 191),
        (199, 199),
        (10, 9),
    ];
    for &(x0, x1) in &spans {
        let mut m = Mask::new(w, 3);
        m.fill_span(1, x0, x1);
        for x in 0..w {
            assert_eq!(
                m.get(x, 1),
                x >= x0 && x <= x1,
                "span {x0}..={x1}, pixel {x}"
            );
            assert!(!m.get(x, 0) && !m.get(x, 2));
        }
        assert!(padding_is_zero(&m));
        let expect = if x1 >= x0 { (x1 - x0 + 1) as u64 } else { 0 };
        assert_eq!(m.count(), expect);
    }
}

#[test]
fn set_get_clear_and_row_range() {
    let mut m = Mask::new(70, 10);
    assert_eq!(m.row_range(), 0..0);
    m.set(69, 7);
    m.set(0, 3);
    assert!(m.get(69, 7) && m.get(0, 3) && !m.get(68, 7));
    assert_eq!(m.row_range(), 3..8);
    assert_eq!(m.count(), 2);
    m.clear();
    assert_eq!(m.count(), 0);
    assert_eq!(m, Mask::new(70, 10));
    assert_eq!(m.row_range(), 0..0);
    m.fill_all();
    assert_eq!(m.count(), 700);
    assert!(padding_is_zero(&m));
    m.clear();
    assert_eq!(m, Mask::new(70, 10));
}

#[test]
fn equality_ignores_row_ranges() {
    let mut a = Mask::new(10, 10);
    a.set(3, 3);
    a.set(4, 8);
    let b = Mask::from_fn(10, 10, |x, y| (x, y) == (3, 3) || (x, y) == (4, 8));
    assert_eq!(a, b);
    let c = Mask::from_fn(10, 10, |x, y| (x, y) == (3, 3));
    assert_ne!(a, c);
}

#[test]
fn every_popcount_kernel_agrees() {
    // The dispatch picks one kernel per machine; check the others here too.
    let mut rng = Rng(7);
    let a = random_mask(&mut rng, 640, 48, 40);
    let b = random_mask(&mut rng, 640, 48, 60);
    let op = |x: u64, y: u64| x ^ y;
    let scalar = pair_count_words(&a.words, &b.words, op);
    assert_eq!(scalar, a.xor_count(&b));
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            assert_eq!(unsafe { pair_count_avx2(&a.words, &b.words, op) }, scalar);
        }
        if std::arch::is_x86_feature_detected!("avx512vpopcntdq") {
            assert_eq!(unsafe { pair_count_avx512(&a.words, &b.words, op) }, scalar);
        }
    }
}

#[test]
fn pair_counts_match_per_pixel_reference() {
    let mut rng = Rng(1);
    for &(w, h) in &[(1, 1), (64, 5), (65, 7), (200, 31), (640, 48)] {
        for _ in 0..5 {
            let a = random_mask(&mut rng, w, h, 40);
            let b = random_mask(&mut rng, w, h, 60);
            let (mut x, mut n, mut an, mut ca) = (0, 0, 0, 0);
            for y in 0..h {
                for i in 0..w {
                    let (p, q) = (a.get(i, y), b.get(i, y));
                    x += (p != q) as u64;
                    n += (p && q) as u64;
                    an += (p && !q) as u64;
                    ca += p as u64;
                }
            }
            assert_eq!(a.xor_count(&b), x);
            assert_eq!(a.and_count(&b), n);
            assert_eq!(a.and_not_count(&b), an);
            assert_eq!(a.count(), ca);
            let d = a.and_not(&b);
            assert_eq!(d.count(), an);
            assert_eq!(d, Mask::from_fn(w, h, |i, y| a.get(i, y) && !b.get(i, y)));
            let mut o = a.clone();
            o.or_assign(&b);
            assert_eq!(o, Mask::from_fn(w, h, |i, y| a.get(i, y) || b.get(i, y)));
            assert_eq!(o.count(), ca + b.count() - n);
        }
    }
    // One empty operand: the union of row ranges must still cover the other mask.
    let e = Mask::new(100, 20);
    let f = Mask::from_fn(100, 20, |x, y| x == y);
    assert_eq!(e.xor_count(&f), 20);
    assert_eq!(f.xor_count(&e), 20);
    assert_eq!(e.and_not_count(&f), 0);
    assert_eq!(f.and_not_count(&e), 20);
}

#[test]
fn moments_of_hand_made_masks() {
    // A single pixel: centre (3.5, 5.5), no spread.
    let mut m = Mask::new(10, 10);
    m.set(3, 5);
    let mo = m.moments();
    assert_eq!(mo.count, 1.0);
    assert_eq!(mo.centroid(), Some(DVec2::new(3.5, 5.5)));
    assert_eq!(mo.sum_xx, 3.5 * 3.5);
    assert_eq!(mo.sum_xy, 3.5 * 5.5);
    assert_eq!(mo.central_second(), Some([0.0, 0.0, 0.0]));

    // An a x b rectangle spanning word boundaries: mu20 = (a^2 - 1) / 12.
    let (x0, x1, y0, y1) = (50usize, 149usize, 7usize, 26usize);
    let r = Mask::from_fn(200, 40, |x, y| {
        (x0..=x1).contains(&x) && (y0..=y1).contains(&y)
    });
    let mo = r.moments();
    let (a, b) = ((x1 - x0 + 1) as f64, (y1 - y0 + 1) as f64);
    assert_eq!(mo.count, a * b);
    let c = mo.centroid().unwrap();
    assert_eq!(
        c,
        DVec2::new((x0 + x1 + 1) as f64 / 2.0, (y0 + y1 + 1) as f64 / 2.0)
    );
    let [m20, m11, m02] = mo.central_second().unwrap();
    assert!((m20 - (a * a - 1.0) / 12.0).abs() < 1e-9, "{m20}");
    assert!(m11.abs() < 1e-9, "{m11}");
    assert!((m02 - (b * b - 1.0) / 12.0).abs() < 1e-9, "{m02}");

    // A diagonal line has positive mu11 (x and y grow together).
    let d = Mask::from_fn(30, 30, |x, y| x == y);
    let [_, m11, _] = d.moments().central_second().unwrap();
    assert!(m11 > 0.0);

    let empty = Mask::new(30, 30).moments();
    assert_eq!(empty.count, 0.0);
    assert_eq!(empty.centroid(), None);
    assert_eq!(empty.central_second(), None);
}

#[test]
fn moments_match_per_pixel_reference() {
    let mut rng = Rng(7);
    // The last two are past 2^15 pixels a side, where the totals are kept in u128.
    for &(w, h) in &[(64, 3), (130, 40), (640, 20), (40_000, 3), (2, 33_000)] {
        for density in [5, 50, 95, 100] {
            let m = random_mask(&mut rng, w, h, density);
            let mut r = Moments::default();
            for y in 0..h {
                for x in 0..w {
                    if m.get(x, y) {
                        let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
                        r.count += 1.0;
                        r.sum_x += fx;
                        r.sum_y += fy;
                        r.sum_xx += fx * fx;
                        r.sum_xy += fx * fy;
                        r.sum_yy += fy * fy;
                    }
                }
            }
            // Both sides are exact integers / quarters well below 2^53.
            assert_eq!(m.moments(), r, "{w}x{h} density {density}");
        }
    }
}

/// Per-pixel reference morphology with "outside counts as 0".
fn morph_reference(m: &Mask, k: usize, erode: bool) -> Mask {
    let r = (k / 2) as isize;
    let (w, h) = (m.width() as isize, m.height() as isize);
    Mask::from_fn(m.width(), m.height(), |x, y| {
        let mut any = false;
        let mut all = true;
        for dy in -r..=r {
            for dx in -r..=r {
                let (xx, yy) = (x as isize + dx, y as isize + dy);
                let v = xx >= 0 && yy >= 0 && xx < w && yy < h && m.get(xx as usize, yy as usize);
                any |= v;
                all &= v;
            }
        }
        if erode {
            all
        } else {
            any
        }
    })
}

#[test]
fn dilate_and_erode_hand_made() {
    // One pixel dilates to a 5x5 square, clipped at the image border.
    let mut m = Mask::new(70, 20);
    m.set(64, 10);
    let d = m.dilate(5);
    assert_eq!(
        d,
        Mask::from_fn(70, 20, |x, y| (62..=66).contains(&x)
            && (8..=12).contains(&y))
    );
    let mut corner = Mask::new(70, 20);
    corner.set(69, 0);
    assert_eq!(corner.dilate(5).count(), 9);
    assert!(padding_is_zero(&corner.dilate(5)));
    // The 5x5 square erodes back to the single pixel.
    assert_eq!(d.erode(5), m);
    // A full mask erodes to everything at least 2 pixels from the border.
    let mut full = Mask::new(70, 20);
    full.fill_all();
    let e = full.erode(5);
    assert_eq!(
        e,
        Mask::from_fn(70, 20, |x, y| (2..68).contains(&x) && (2..18).contains(&y))
    );
    assert_eq!(full.dilate(5), full);
    assert_eq!(full.erode(1), full);
    assert_eq!(Mask::new(70, 20).dilate(5), Mask::new(70, 20));
}

#[test]
fn dilate_and_erode_match_reference() {
    let mut rng = Rng(3);
    for &(w, h) in &[(10, 10), (64, 12), (130, 25)] {
        for k in [1, 3, 5, 7] {
            for density in [30, 90] {
                let m = random_mask(&mut rng, w, h, density);
                assert_eq!(
                    m.dilate(k),
                    morph_reference(&m, k, false),
                    "dilate {w}x{h} k={k}"
                );
                assert_eq!(
                    m.erode(k),
                    morph_reference(&m, k, true),
                    "erode {w}x{h} k={k}"
                );
                assert!(padding_is_zero(&m.dilate(k)));
            }
        }
    }
}

#[test]
fn padded_then_cropped_is_the_same_mask() {
    let mut rng = Rng(41);
    for (w, h, m) in [(70, 50, 18), (64, 64, 16), (130, 9, 33), (5, 3, 0)] {
        let a = random_mask(&mut rng, w, h, 30);
        let p = a.padded(m);
        assert_eq!((p.width(), p.height()), (w + 2 * m, h + 2 * m));
        assert_eq!(p.count(), a.count());
        assert!(padding_is_zero(&p));
        for y in 0..h {
            for x in 0..w {
                assert_eq!(p.get(x + m, y + m), a.get(x, y));
            }
        }
        assert_eq!(p.cropped(m), a);
        // Pixels in the margin are cut off.
        let mut q = p.clone();
        if m > 0 {
            q.set(0, 0);
            q.set(w + 2 * m - 1, h + m);
        }
        assert_eq!(q.cropped(m), a);
    }
}

#[test]
fn connected_to_keeps_the_components_a_seed_touches() {
    // Three bars: the seed touches the first and the third, through one pixel each.
    let m = Mask::from_fn(150, 40, |x, y| {
        (y == 3 && x < 120) || (x == 70 && (10..30).contains(&y)) || (y == 35 && x >= 60)
    });
    let seed = Mask::from_fn(150, 40, |x, y| {
        (x, y) == (5, 3) || (x, y) == (149, 35) || (x, y) == (0, 0)
    });
    let got = m.connected_to(&seed);
    let want = Mask::from_fn(150, 40, |x, y| (y == 3 && x < 120) || (y == 35 && x >= 60));
    assert_eq!(got, want);
    assert_eq!(m.connected_to(&Mask::new(150, 40)).count(), 0);
    assert_eq!(m.and(&seed).count(), 2);
}

#[test]
fn counts_and_moment_sums_of_disjoint_rows_add_up_to_the_whole() {
    let mut rng = Rng(29);
    for (w, h) in [(1, 1), (63, 7), (64, 40), (130, 33)] {
        for _ in 0..8 {
            let (a, b) = (
                random_mask(&mut rng, w, h, 3),
                random_mask(&mut rng, w, h, 2),
            );
            let k = rng.below(h + 1);
            let (top, rest) = (0..k, k..usize::MAX);
            assert_eq!(
                a.count_in(top.clone()) + a.count_in(rest.clone()),
                a.count()
            );
            assert_eq!(
                a.xor_count_in(&b, top.clone()) + a.xor_count_in(&b, rest.clone()),
                a.xor_count(&b)
            );
            assert_eq!(
                a.and_count_in(&b, top.clone()) + a.and_count_in(&b, rest.clone()),
                a.and_count(&b)
            );
            assert_eq!(
                a.and_not_count_in(&b, top.clone()) + a.and_not_count_in(&b, rest.clone()),
                a.and_not_count(&b)
            );
            let whole = a.moment_sums(0..usize::MAX);
            let (t, r) = (a.moment_sums(top), a.moment_sums(rest));
            assert_eq!(whole.0, std::array::from_fn(|i| t.0[i] + r.0[i]));
            assert_eq!(Moments::from_sums(whole), a.moments());
        }
    }
}

#[test]
fn drawn_rows_are_the_rows_a_drawing_set_pixels_in() {
    let mut m = Mask::new(100, 50);
    m.fill_span(3, 0, 10);
    m.fill_span(40, 5, 6);
    let drawn = m.drawn_rows(|m| {
        m.fill_span(20, 1, 2);
        m.set(25, 31);
    });
    assert_eq!(drawn, 20..32);
    // The mask's own range still covers everything set.
    assert_eq!(m.row_range(), 3..41);
    assert_eq!(m.drawn_rows(|_| {}), 0..0);
    assert_eq!(m.row_range(), 3..41);
}

#[test]
fn restoring_the_rows_drawn_over_a_copy_gives_the_copy_back() {
    let mut rng = Rng(7);
    for _ in 0..20 {
        let base = random_mask(&mut rng, 130, 40, 30);
        let mut m = Mask::new(130, 40);
        m.copy_from(&base);
        let (y0, y1) = (rng.below(40), rng.below(40));
        let drawn = m.drawn_rows(|m| {
            m.fill_span(y0, rng.below(60), 60 + rng.below(70));
            m.fill_span(y1, 3, 3);
        });
        m.restore_rows(&base, drawn);
        assert_eq!(m, base);
        assert_eq!(m.row_range(), base.row_range());
    }
}
