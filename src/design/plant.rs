//! Planted problems: a random launch of a box of objects whose shadow at `t` becomes the
//! target, so that a perfect answer exists by construction. They measure the solver on
//! problems nobody tuned it for (`bsa plant`, `scripts/planted-suite.sh`).
//!
//! Data flow: [`Layout`] places the objects on the floor in front of the picture and
//! writes the scene file ([`Layout::scene_json`]); once that scene is loaded (with a
//! placeholder target), [`draw_launch`] draws launches until one is contact-free, casts
//! every shadow inside the picture and leaves each object's shadow visible; its shadow is
//! the target; [`hints`] then places one hint per object the way a user would, from the
//! target alone: each object's centre to the centroid of a blob, objects and blobs
//! matched by size.

use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{json, Value};

use super::inventory::{Item, Kind};
use crate::energy::Weights;
use crate::evaluate::Problem;
use crate::geometry::shape::{ObjError, TriMesh};
use crate::scene::{velocity_reaching, Launch};
use crate::shadow::mask::Mask;

/// The stage of a planted (or designed) scene: what `bsa plant` and `bsa new` lay out.
#[derive(Clone, Debug)]
pub struct Stage {
    /// Width of the picture on the floor (m); its height follows the target's aspect.
    pub picture_width: f64,
    /// Height of the point light above the picture's centre (m).
    pub light_height: f64,
    /// The instant of the picture (s).
    pub t: f64,
    /// Target size in pixels.
    pub pixels: (usize, usize),
}

impl Default for Stage {
    fn default() -> Stage {
        Stage {
            picture_width: 1.6,
            light_height: 6.0,
            t: 1.2,
            pixels: (640, 480),
        }
    }
}

impl Stage {
    /// Height of the picture on the floor (m), from the target's aspect ratio.
    pub fn picture_height(&self) -> f64 {
        self.picture_width * self.pixels.1 as f64 / self.pixels.0 as f64
    }

    /// A scene file of this stage: the picture on the floor under the light, the table,
    /// `occluders` (scene-file JSON) and the target file `target`, with the default
    /// strategy for `objects` objects.
    pub fn scene_json(
        &self,
        name: &str,
        target: &str,
        occluders: Vec<Value>,
        objects: usize,
    ) -> Value {
        json!({
            "name": name,
            "target": target,
            "t": self.t,
            "light": [0.0, 0.0, self.light_height],
            "receiver": {"center": [0.0, 0.0, 0.0], "u": [1.0, 0.0, 0.0], "v": [0.0, 1.0, 0.0],
                         "width": self.picture_width, "height": self.picture_height()},
            "table": {"center": [0.0, 0.0, -0.5], "size": [40.0, 40.0, 1.0]},
            "occluders": occluders,
            "strategy": default_strategy(objects),
        })
    }
}

/// Why a problem cannot be planted.
#[derive(Debug, thiserror::Error)]
pub enum PlantError {
    /// An OBJ of the inventory cannot be used.
    #[error("cannot use the mesh {path}")]
    Mesh {
        path: String,
        #[source]
        source: ObjError,
    },
    /// A chess piece by name (only `bsa new` writes the built-in set's meshes).
    #[error("chess:{piece}: bsa plant takes the chess pieces as meshes (mesh:scenes/thinker/pieces/{piece}.obj)")]
    Chess { piece: String },
    /// No draw met the conditions.
    #[error("no launch in {attempts} draws keeps these {objects} objects clear of each other with every shadow inside the picture and visible: the inventory does not fit in a {width} m picture (use fewer or smaller objects, or a wider picture)")]
    NoFit {
        attempts: usize,
        objects: usize,
        width: f64,
    },
}

/// A mesh of the inventory as the caller read it (the command line, with the OBJ
/// reader): `design` touches no file itself.
pub struct MeshFile {
    /// The mesh, scaled.
    pub mesh: TriMesh,
    /// The path the scene names it by: absolute, so that the scene written elsewhere
    /// finds it.
    pub path: std::path::PathBuf,
}

/// How [`Layout::new`] reads a mesh: (OBJ path as the list gives it, scale) to the mesh.
pub type ReadMesh<'a> = &'a dyn Fn(&std::path::Path, f64) -> Result<MeshFile, ObjError>;

/// The objects of an inventory placed on the floor, ready to be written as a scene.
#[derive(Clone, Debug)]
pub struct Layout {
    pub stage: Stage,
    /// (name, shape JSON, launch position, density) per object.
    objects: Vec<(String, Value, DVec3, f64)>,
}

impl Layout {
    /// Place `items` in rows on the floor, in front of the picture (negative y), each
    /// resting on it; `read_mesh` reads the meshes' files.
    pub fn new(stage: Stage, items: &[Item], read_mesh: ReadMesh) -> Result<Layout, PlantError> {
        let h = stage.picture_height();
        let mut objects = Vec::new();
        let (mut x, mut y, mut row_depth) = (0.0f64, -(0.5 * h + 0.5), 0.0f64);
        let row_length = 2.0 * stage.picture_width;
        let mut counts = std::collections::HashMap::new();
        let (mut rows, mut row) = (Vec::new(), 0usize);
        for item in items {
            // Footprint (x, y extent) and the height of the origin above the floor.
            let (shape, foot, lift, stem) = match &item.kind {
                Kind::Sphere { radius } => (
                    json!({"sphere": {"radius": radius}}),
                    DVec2::splat(2.0 * radius),
                    *radius,
                    "sphere".to_string(),
                ),
                Kind::Box { size } => (
                    json!({"box": {"size": size}}),
                    DVec2::new(size[0], size[1]),
                    0.5 * size[2],
                    "box".to_string(),
                ),
                Kind::Chess { piece } => {
                    return Err(PlantError::Chess {
                        piece: piece.clone(),
                    })
                }
                Kind::Mesh { obj, scale } => {
                    let MeshFile { mesh, path: abs } =
                        read_mesh(obj, *scale).map_err(|source| PlantError::Mesh {
                            path: obj.display().to_string(),
                            source,
                        })?;
                    let (mut lo, mut hi) =
                        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
                    for v in &mesh.vertices {
                        lo = lo.min(*v);
                        hi = hi.max(*v);
                    }
                    (
                        json!({"mesh": {"obj": abs.display().to_string(), "scale": scale}}),
                        (hi - lo).truncate(),
                        -lo.z,
                        obj.file_stem()
                            .and_then(|s| s.to_str())
                            .unwrap_or("mesh")
                            .to_string(),
                    )
                }
            };
            let n = counts.entry(stem.clone()).or_insert(0);
            *n += 1;
            let name = format!("{stem}_{n}");
            // Room between neighbours, so that the start guesses, which send them off in
            // different directions, do not meet right after the launch.
            let gap = (0.5 * foot.x.max(foot.y)).max(0.05);
            if x > 0.0 && x + foot.x > row_length {
                x = 0.0;
                y -= row_depth + gap;
                row_depth = 0.0;
                row += 1;
            }
            let cx = x + 0.5 * foot.x;
            x += foot.x + gap;
            row_depth = row_depth.max(foot.y);
            // Rows are centred afterwards; y is the row's front edge.
            objects.push((
                name,
                shape,
                DVec3::new(cx, y - 0.5 * foot.y, lift + 1e-6),
                item.density,
            ));
            rows.push(row);
        }
        // Centre every row on x = 0.
        for r in 0..=row {
            let members: Vec<usize> = (0..objects.len()).filter(|&j| rows[j] == r).collect();
            let (lo, hi) = members
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &j| {
                    (a.min(objects[j].2.x), b.max(objects[j].2.x))
                });
            for &j in &members {
                objects[j].2.x -= 0.5 * (lo + hi);
            }
        }
        Ok(Layout { stage, objects })
    }

    /// Number of objects.
    pub fn len(&self) -> usize {
        self.objects.len()
    }

    /// Whether there are no objects.
    pub fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }

    /// The scene file: geometry, the objects, the target file `target`, `hints` as
    /// (occluder index, point in the body's frame, pixel), and the default strategy for
    /// this many objects.
    pub fn scene_json(
        &self,
        name: &str,
        target: &str,
        hints: &[(usize, DVec3, DVec2)],
        seed: u64,
    ) -> Value {
        let s = &self.stage;
        let occluders: Vec<Value> = self
            .objects
            .iter()
            .map(|(name, shape, p, density)| {
                json!({"name": name, "shape": shape, "position": [p.x, p.y, p.z], "density": density})
            })
            .collect();
        let hints: Vec<Value> = hints
            .iter()
            .map(|(i, p, px)| {
                json!({"occluder": self.objects[*i].0, "point": [p.x, p.y, p.z], "pixel": [px.x, px.y]})
            })
            .collect();
        let mut scene = s.scene_json(name, target, occluders, self.objects.len());
        scene["seed"] = seed.into();
        if !hints.is_empty() {
            scene["hints"] = Value::from(hints);
        }
        scene
    }
}

/// The strategy a designed scene gets: one object at a time, then all together (for
/// more than four objects, the pass one at a time runs four times: each pass still
/// gains where bodies that moved in the last one left room), with the default weights
/// ([`Weights::default_for`]) and contacts as constraints.
pub fn default_strategy(objects: usize) -> Value {
    if objects <= 4 {
        return json!({"kind": "sequential", "order": "auto", "rounds": 1,
            "stage": {"step": 0.1, "population": 24, "max_iterations": 100, "stagnation": 30},
            "final": {"step": 0.05, "population": 32, "max_iterations": 150, "stagnation": 40}});
    }
    json!({"kind": "sequential", "order": "auto", "rounds": 4,
        "stage": {"step": 0.05, "population": 24, "max_iterations": 100, "stagnation": 25},
        "final": {"step": 0.02, "population": 32, "max_iterations": 100, "stagnation": 25}})
}

/// Draw launches for every launched occluder of `problem` until one flies clear of
/// everything, casts every shadow inside the picture and leaves each object at least
/// a third of its own shadow visible. Each occluder is sent through a random point of
/// the picture's central part, at a random height between a fifth and a half of the
/// light's, with a random spin of up to 4 rad/s.
pub fn draw_launch(problem: &Problem, seed: u64, attempts: usize) -> Result<Vec<f64>, PlantError> {
    let scene = &problem.scene;
    let cam = &scene.camera;
    let n = scene.occluders.len();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut ws = problem.workspace();
    let mut params = vec![0.0; scene.variable_count()];
    let light = cam.light;
    let t = scene.t;
    for _ in 0..attempts {
        for (i, o) in scene.occluders.iter().enumerate() {
            if !o.launched {
                continue;
            }
            let px = rng.random_range(0.15..0.85) * cam.width_px as f64;
            let py = rng.random_range(0.15..0.85) * cam.height_px as f64;
            let on_plane = cam.pixel_to_world(px, py);
            let s = rng.random_range(0.2..0.5);
            let com_t = on_plane + s * (light - on_plane);
            let com0 = o.launch_com();
            let v = velocity_reaching(com0, com_t, scene.gravity, t);
            let axis = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize_or_zero();
            let w = axis * rng.random_range(0.5..4.0);
            Launch {
                velocity: v,
                angular_velocity: w,
            }
            .set(&mut params, i);
        }
        let e = problem.evaluate(&params, &Weights::default(), &mut ws);
        if e.outcome.n_contacts > 0 || !problem.shadows_in_image(&ws).iter().all(|&b| b) {
            continue;
        }
        let full = ws.mask.count();
        let visible = (0..n).all(|i| {
            let mut only = vec![false; n];
            only[i] = true;
            problem.shadow_only(&only, &mut ws);
            let alone = ws.mask.count();
            let mut others: Vec<bool> = vec![true; n];
            others[i] = false;
            problem.shadow_only(&others, &mut ws);
            let rest = ws.mask.count();
            alone > 0 && (full - rest) as f64 >= alone as f64 / 3.0
        });
        if visible {
            return Ok(params);
        }
    }
    Err(PlantError::NoFit {
        attempts,
        objects: n,
        width: scene.receiver.width,
    })
}

/// One hint per object from the target alone, as a user would place them: the target's
/// blobs (4-connected) and the objects are each sorted by size (blob area, object
/// volume); while some blob has no object, the largest object left takes the largest
/// blob left, so that every blob is covered; the objects beyond take, in turn, the
/// blob with the most area per object already on it. A hint sends the object's centre
/// of mass (its point, in the body's frame) to its blob's centroid.
pub fn hints(problem: &Problem, target: &Mask) -> Vec<(usize, DVec3, DVec2)> {
    let mut blobs = target.blobs();
    if blobs.is_empty() {
        return Vec::new();
    }
    blobs.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.x.total_cmp(&b.1.x)));
    let occ = &problem.scene.occluders;
    let order = crate::scene::auto_order(occ);
    let mut taken = vec![0usize; blobs.len()];
    let mut out = Vec::new();
    for (rank, i) in order.into_iter().enumerate() {
        let k = if rank < blobs.len() {
            rank
        } else {
            (0..blobs.len())
                .max_by(|&a, &b| {
                    let share = |k: usize| blobs[k].0 as f64 / (1 + taken[k]) as f64;
                    share(a).total_cmp(&share(b)).then(b.cmp(&a))
                })
                .expect("at least one blob")
        };
        taken[k] += 1;
        out.push((i, occ[i].mass.local_com, blobs[k].1));
    }
    out.sort_by_key(|h| h.0);
    out
}
