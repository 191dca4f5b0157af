//! The accuracy report: its statistics (nearest-rank percentiles, explained disagreements, closest-hit and
//! shadow-ray counts), the table and the JSON object.

use std::fmt::Write as _;

use super::{EPS32, K_GRAZE, K_SELF, K_START, K_TIE};

/// Nearest-rank percentiles of a list of values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Percentiles {
    /// How many values.
    pub(crate) count: u64,
    /// Median (NaN when there are no values).
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// 99.9th percentile.
    pub(crate) p999: f64,
    /// Largest value.
    pub max: f64,
}

impl Percentiles {
    /// Sorts `values` and takes the nearest-rank percentiles: the p-th is the ⌈p·n⌉-th smallest.
    pub fn of(mut values: Vec<f64>) -> Self {
        values.sort_by(f64::total_cmp);
        let n = values.len();
        let rank =
            |p: f64| if n == 0 { f64::NAN } else { values[((p * n as f64).ceil() as usize).clamp(1, n) - 1] };
        Self { count: n as u64, p50: rank(0.5), p99: rank(0.99), p999: rank(0.999), max: rank(1.0) }
    }
}

/// How many disagreements each explanation accounted for (each counted once, under the first that holds,
/// in this order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Explained {
    /// Tangency with either primitive.
    pub(crate) graze: u64,
    /// Both primitives hit at nearly the same t.
    pub(crate) tie: u64,
    /// The ray starts on either primitive's surface.
    pub(crate) start: u64,
    /// The light lies on the blocker's surface (shadow rays).
    pub(crate) light: u64,
    /// The light is within rounding of the surface's tangent plane (shadow rays).
    pub(crate) facing: u64,
    /// Explained only with the tolerances widened by the f32 ray's measured divergence.
    pub(crate) diverge: u64,
}

impl Explained {
    /// All explained disagreements.
    pub(crate) fn total(&self) -> u64 {
        self.graze + self.tie + self.start + self.light + self.facing + self.diverge
    }
    pub(super) fn add(&mut self, o: &Explained) {
        self.graze += o.graze;
        self.tie += o.tie;
        self.start += o.start;
        self.light += o.light;
        self.facing += o.facing;
        self.diverge += o.diverge;
    }
    pub(super) fn count(&mut self, r: Reason) {
        match r {
            Reason::Graze => self.graze += 1,
            Reason::Tie => self.tie += 1,
            Reason::Start => self.start += 1,
            Reason::Light => self.light += 1,
            Reason::Facing => self.facing += 1,
            Reason::Diverge => self.diverge += 1,
        }
    }
}

/// Why a disagreement is explained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Reason {
    Graze,
    Tie,
    Start,
    Light,
    Facing,
    Diverge,
}

/// Closest-hit rays of one kind (primary, mirror or refraction) compared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct HitStats {
    /// Rays traced in both precisions.
    pub(crate) rays: u64,
    /// Both hit the same primitive.
    pub(crate) hits_agree: u64,
    /// Both missed.
    pub(crate) misses_agree: u64,
    /// One hit, the other missed.
    pub(crate) hit_miss_disagree: u64,
    /// Both hit, different primitives.
    pub(crate) id_disagree: u64,
    /// Refraction rays only: total internal reflection in one precision, a refracted ray in the other (the
    /// ray is traced in neither; not counted in `rays`).
    pub(crate) tir_disagree: u64,
    /// Disagreements explained, by reason.
    pub(crate) explained: Explained,
    /// Disagreements not explained.
    pub(crate) unexplained: u64,
    /// Self-hits (secondary rays only).
    pub(crate) self_hits: u64,
    /// Relative t error over the rays whose hits agree.
    pub(crate) t_rel_err: Percentiles,
}

impl HitStats {
    /// All disagreements.
    pub(crate) fn disagree(&self) -> u64 {
        self.hit_miss_disagree + self.id_disagree + self.tir_disagree
    }
}

/// Shadow rays compared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct ShadowStats {
    /// Shadow rays compared: lights in front of the surface in both precisions (each traced in both, but for
    /// those of [`ShadowStats::seen_from_eye`], which the f32 side sees unblocked as shading does).
    pub(crate) rays: u64,
    /// Of those, rays from a camera ray's hit toward a light at the eye, which shading does not trace (the
    /// light is seen): unblocked on the f32 side, traced by the twin alone.
    pub(crate) seen_from_eye: u64,
    /// Lights in front of the surface in one precision only (a shadow ray in one only).
    pub(crate) lit_disagree: u64,
    /// Occluded in one precision only.
    pub(crate) occluded_disagree: u64,
    /// Disagreements explained, by reason.
    pub(crate) explained: Explained,
    /// Disagreements not explained.
    pub(crate) unexplained: u64,
    /// Shadow rays blocked by their own departure primitive, or at their origin, in one precision only.
    pub(crate) self_hits: u64,
}

impl ShadowStats {
    /// All disagreements.
    pub(crate) fn disagree(&self) -> u64 {
        self.lit_disagree + self.occluded_disagree
    }
    pub(super) fn add(&mut self, o: &ShadowStats) {
        self.rays += o.rays;
        self.seen_from_eye += o.seen_from_eye;
        self.lit_disagree += o.lit_disagree;
        self.occluded_disagree += o.occluded_disagree;
        self.explained.add(&o.explained);
        self.unexplained += o.unexplained;
        self.self_hits += o.self_hits;
    }
}

/// One unexplained disagreement or self-hit, for the report.
#[derive(Clone, Debug, PartialEq)]
pub struct Example {
    /// `primary`, `reflection`, `refraction` or `shadow`, with ` self-hit` for self-hits (`shadow facing`,
    /// `refraction tir`: the side or the total internal reflection disagreed; t holds the cosine or `sin²`).
    pub(crate) kind: String,
    /// Pixel column.
    pub(crate) x: u32,
    /// Pixel row.
    pub(crate) y: u32,
    /// The light's index for shadow rays.
    pub(crate) light: Option<usize>,
    /// The f32 hit (or shadow blocker): scene-file id, −1 for none, and t.
    pub(crate) f32_hit: (i64, f64),
    /// The f64 twin's.
    pub(crate) f64_hit: (i64, f64),
}

/// The comparison of one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// The scene's name (as given to [`super::run`]).
    pub(crate) scene: String,
    /// Image columns.
    pub(crate) width: u32,
    /// Image rows.
    pub(crate) height: u32,
    /// Packet width of the f32 primary pass.
    pub(crate) lanes: usize,
    /// Whether the f32 pass ran on the scalar path (`lanes` is then 1; JSON writes `"lanes":"scalar"`).
    pub(crate) scalar: bool,
    /// Primitives in the scene.
    pub(crate) primitives: usize,
    /// Whether the twin searched spheres through its BVH.
    pub(crate) twin_bvh: bool,
    /// Camera rays.
    pub(crate) primary: HitStats,
    /// Shadow rays (with secondary rays).
    pub(crate) shadow: Option<ShadowStats>,
    /// Mirror rays (with secondary rays).
    pub(crate) reflection: Option<HitStats>,
    /// Refraction rays (with secondary rays): from hits on transmitting materials.
    pub(crate) refraction: Option<HitStats>,
    /// Some unexplained disagreements and self-hits.
    pub(crate) examples: Vec<Example>,
    /// Wall-clock seconds of the whole comparison (compile and twin build included).
    pub(crate) seconds: f64,
}

impl Report {
    /// Unexplained disagreements of every kind.
    pub(crate) fn unexplained(&self) -> u64 {
        self.primary.unexplained
            + self.shadow.map_or(0, |s| s.unexplained)
            + self.reflection.map_or(0, |r| r.unexplained)
            + self.refraction.map_or(0, |r| r.unexplained)
    }

    /// Self-hits of every kind.
    pub(crate) fn self_hits(&self) -> u64 {
        self.shadow.map_or(0, |s| s.self_hits)
            + self.reflection.map_or(0, |r| r.self_hits)
            + self.refraction.map_or(0, |r| r.self_hits)
    }

    /// One JSON object (one line): the keys are listed in README.md's `accuracy` section.
    pub fn to_json(&self) -> String {
        let mut o = String::from("{");
        let mut put = |k: &str, v: String| {
            if o.len() > 1 {
                o.push(',');
            }
            let _ = write!(o, "\"{k}\":{v}");
        };
        put("scene", json_str(&self.scene));
        put("width", self.width.to_string());
        put("height", self.height.to_string());
        put("lanes", if self.scalar { json_str("scalar") } else { self.lanes.to_string() });
        put("primitives", self.primitives.to_string());
        put("twin_bvh", self.twin_bvh.to_string());
        put("secondary", self.shadow.is_some().to_string());
        put("k_graze", num(K_GRAZE));
        put("k_tie", num(K_TIE));
        put("k_start", num(K_START));
        put("k_self", num(K_SELF));
        put("eps32", num(EPS32));
        let p = &self.primary;
        put("rays", p.rays.to_string());
        put("hits_agree", p.hits_agree.to_string());
        put("misses_agree", p.misses_agree.to_string());
        put("hit_miss_disagree", p.hit_miss_disagree.to_string());
        put("id_disagree", p.id_disagree.to_string());
        put("explained_disagree", p.explained.total().to_string());
        put("explained_graze", p.explained.graze.to_string());
        put("explained_tie", p.explained.tie.to_string());
        put("unexplained_disagree", p.unexplained.to_string());
        put("t_rel_err_count", p.t_rel_err.count.to_string());
        put("t_rel_err_p50", num(p.t_rel_err.p50));
        put("t_rel_err_p99", num(p.t_rel_err.p99));
        put("t_rel_err_p999", num(p.t_rel_err.p999));
        put("t_rel_err_max", num(p.t_rel_err.max));
        put("self_hits", self.self_hits().to_string());
        put("unexplained_total", self.unexplained().to_string());
        if let Some(s) = &self.shadow {
            put("shadow_rays", s.rays.to_string());
            put("shadow_seen_from_eye", s.seen_from_eye.to_string());
            put("shadow_disagree", s.disagree().to_string());
            put("shadow_lit_disagree", s.lit_disagree.to_string());
            put("shadow_occluded_disagree", s.occluded_disagree.to_string());
            put("shadow_explained", s.explained.total().to_string());
            put("shadow_explained_graze", s.explained.graze.to_string());
            put("shadow_explained_start", s.explained.start.to_string());
            put("shadow_explained_light", s.explained.light.to_string());
            put("shadow_explained_facing", s.explained.facing.to_string());
            put("shadow_explained_diverge", s.explained.diverge.to_string());
            put("shadow_unexplained", s.unexplained.to_string());
            put("shadow_self_hits", s.self_hits.to_string());
        }
        for (name, stats) in [("reflection", &self.reflection), ("refraction", &self.refraction)] {
            let Some(r) = stats else { continue };
            let mut put_row = |k: &str, v: String| put(&format!("{name}_{k}"), v);
            put_row("rays", r.rays.to_string());
            put_row("hits_agree", r.hits_agree.to_string());
            put_row("disagree", r.disagree().to_string());
            put_row("hit_miss_disagree", r.hit_miss_disagree.to_string());
            put_row("id_disagree", r.id_disagree.to_string());
            if name == "refraction" {
                put_row("tir_disagree", r.tir_disagree.to_string());
            }
            put_row("explained", r.explained.total().to_string());
            put_row("explained_graze", r.explained.graze.to_string());
            put_row("explained_tie", r.explained.tie.to_string());
            put_row("explained_start", r.explained.start.to_string());
            put_row("explained_diverge", r.explained.diverge.to_string());
            put_row("unexplained", r.unexplained.to_string());
            put_row("self_hits", r.self_hits.to_string());
            put_row("t_rel_err_p50", num(r.t_rel_err.p50));
            put_row("t_rel_err_p99", num(r.t_rel_err.p99));
            put_row("t_rel_err_p999", num(r.t_rel_err.p999));
            put_row("t_rel_err_max", num(r.t_rel_err.max));
        }
        let examples: Vec<String> = self
            .examples
            .iter()
            .map(|e| {
                format!(
                    "{{\"kind\":{},\"x\":{},\"y\":{},\"light\":{},\"f32_prim\":{},\"f32_t\":{},\"f64_prim\":{},\"f64_t\":{}}}",
                    json_str(&e.kind),
                    e.x,
                    e.y,
                    e.light.map_or("null".to_owned(), |l| l.to_string()),
                    e.f32_hit.0,
                    num(e.f32_hit.1),
                    e.f64_hit.0,
                    num(e.f64_hit.1)
                )
            })
            .collect();
        put("examples", format!("[{}]", examples.join(",")));
        put("seconds", format!("{:.3}", self.seconds));
        o.push('}');
        o
    }

    /// The human-readable table.
    pub fn table(&self) -> String {
        let mut o = String::new();
        let _ = writeln!(
            o,
            "{}: {}x{}, {} primitives, f32 {} against the f64 twin ({}), {:.2} s",
            self.scene,
            self.width,
            self.height,
            self.primitives,
            if self.scalar { "scalar path".to_owned() } else { format!("packets of {}", self.lanes) },
            if self.twin_bvh { "BVH" } else { "brute force" },
            self.seconds
        );
        let _ = writeln!(
            o,
            "tolerances in eps32 = 2^-24 of the magnitudes involved: graze/facing k = {K_GRAZE}, tie k = {K_TIE}, \
             start/light k = {K_START}, self-hit k = {K_SELF}"
        );
        let _ = writeln!(
            o,
            "{:<10} {:>10} {:>10} {:>9} {:>8} {:>9} {:>11} {:>9}   {:>9} {:>9} {:>9}",
            "rays",
            "count",
            "agree",
            "hit/miss",
            "id",
            "explained",
            "unexplained",
            "self-hits",
            "t err p50",
            "p99",
            "max"
        );
        let hit_row = |o: &mut String, name: &str, s: &HitStats| {
            let _ = writeln!(
                o,
                "{:<10} {:>10} {:>10} {:>9} {:>8} {:>9} {:>11} {:>9}   {:>9} {:>9} {:>9}",
                name,
                s.rays,
                s.hits_agree + s.misses_agree,
                s.hit_miss_disagree,
                s.id_disagree,
                s.explained.total(),
                s.unexplained,
                if name == "primary" { "-".to_owned() } else { s.self_hits.to_string() },
                sci(s.t_rel_err.p50),
                sci(s.t_rel_err.p99),
                sci(s.t_rel_err.max)
            );
        };
        hit_row(&mut o, "primary", &self.primary);
        if let Some(s) = &self.shadow {
            let _ = writeln!(
                o,
                "{:<10} {:>10} {:>10} {:>9} {:>8} {:>9} {:>11} {:>9}",
                "shadow",
                s.rays,
                s.rays - s.occluded_disagree,
                s.occluded_disagree,
                format!("lit {}", s.lit_disagree),
                s.explained.total(),
                s.unexplained,
                s.self_hits
            );
        }
        if let Some(r) = &self.reflection {
            hit_row(&mut o, "reflection", r);
        }
        if let Some(r) = &self.refraction {
            hit_row(&mut o, "refraction", r);
        }
        let why = |e: &Explained| {
            format!(
                "graze {}, tie {}, start {}, light {}, facing {}, diverge {}",
                e.graze, e.tie, e.start, e.light, e.facing, e.diverge
            )
        };
        let _ = writeln!(o, "explained primary: {}", why(&self.primary.explained));
        if let Some(s) = &self.shadow {
            let _ = writeln!(o, "explained shadow: {}", why(&s.explained));
            if s.seen_from_eye > 0 {
                let _ = writeln!(
                    o,
                    "shadow rays toward a light at the eye from camera hits: {} (shading sees the light without \
                     them; only the twin traces them)",
                    s.seen_from_eye
                );
            }
        }
        if let Some(r) = &self.reflection {
            let _ = writeln!(o, "explained reflection: {}", why(&r.explained));
        }
        if let Some(r) = &self.refraction {
            let _ = writeln!(
                o,
                "explained refraction: {}; total internal reflection in one precision only: {}",
                why(&r.explained),
                r.tir_disagree
            );
        }
        let _ = writeln!(
            o,
            "primary t rel err: {} agreeing hits, p99.9 {}; unexplained {}, self-hits {}",
            self.primary.t_rel_err.count,
            sci(self.primary.t_rel_err.p999),
            self.unexplained(),
            self.self_hits()
        );
        for e in &self.examples {
            let light = e.light.map_or(String::new(), |l| format!(" light {l}"));
            let _ = writeln!(
                o,
                "  {} at ({}, {}){light}: f32 {} t={} / f64 {} t={}",
                e.kind, e.x, e.y, e.f32_hit.0, e.f32_hit.1, e.f64_hit.0, e.f64_hit.1
            );
        }
        o
    }
}

fn sci(v: f64) -> String {
    if v.is_nan() {
        "-".to_owned()
    } else {
        format!("{v:.2e}")
    }
}

/// A JSON number, `null` when not finite.
fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:e}")
    } else {
        "null".to_owned()
    }
}

/// A JSON string.
fn json_str(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(o, "\\u{:04x}", c as u32);
            }
            c => o.push(c),
        }
    }
    o.push('"');
    o
}
