//! `bareray bench --compare OLD.json`: an earlier run's rows read back, matched with this run's by (lanes,
//! threads), and the old and new speeds printed side by side.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context, Result};
use serde::Deserialize;

use super::values::LanesArg;

/// The fields of an old `--json` line that `--compare` reads (the others are ignored).
#[derive(Deserialize)]
struct OldRow {
    lanes: LanesArg,
    threads: usize,
    mrays_per_s: f64,
    scene: Option<String>,
    primary_only: Option<bool>,
    width: Option<u32>,
    height: Option<u32>,
    pattern: Option<String>,
    max_depth: Option<u32>,
}

/// The rows of an old `--json` output by (lanes, threads): Mrays/s of each (several when runs were
/// appended to one file), and the first row, for its settings.
pub(super) struct Old {
    pub(super) path: PathBuf,
    pub(super) rows: BTreeMap<(LanesArg, usize), Vec<f64>>,
    first: OldRow,
}

impl Old {
    pub(super) fn read(path: &Path) -> Result<Old> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read the --compare file", path.display()))?;
        let mut rows: BTreeMap<(LanesArg, usize), Vec<f64>> = BTreeMap::new();
        let mut first = None;
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let row: OldRow = serde_json::from_str(line)
                .map_err(|e| anyhow!("{}:{}: not a bench --json line: {e}", path.display(), i + 1))?;
            rows.entry((row.lanes, row.threads)).or_default().push(row.mrays_per_s);
            first.get_or_insert(row);
        }
        let first = first.ok_or_else(|| anyhow!("{}: holds no bench --json lines", path.display()))?;
        Ok(Old { path: path.to_owned(), rows, first })
    }

    /// The old Mrays/s of a setting (the median when the file holds several) and how many rows it had.
    pub(super) fn mrays(&self, lanes: LanesArg, threads: usize) -> Option<(f64, usize)> {
        let v = self.rows.get(&(lanes, threads))?;
        Some((bareray::bench::min_median_max(v).1, v.len()))
    }

    /// Settings in which the old run differs from this one, for a note (keys missing in the old file
    /// are not compared).
    pub(super) fn differences(&self, now: &Setting) -> Vec<String> {
        fn differs<T: PartialEq + std::fmt::Debug>(d: &mut Vec<String>, key: &str, old: &Option<T>, now: &T) {
            if let Some(old) = old.as_ref().filter(|&o| o != now) {
                d.push(format!("{key} {old:?} (now {now:?})"));
            }
        }
        let f = &self.first;
        let mut d = Vec::new();
        differs(&mut d, "scene", &f.scene, &now.scene);
        differs(&mut d, "primary_only", &f.primary_only, &now.primary_only);
        differs(&mut d, "width", &f.width, &now.width);
        differs(&mut d, "height", &f.height, &now.height);
        differs(&mut d, "pattern", &f.pattern, &now.pattern);
        differs(&mut d, "max_depth", &f.max_depth, &now.max_depth);
        d
    }
}

/// What a bench run measures, besides lanes and threads: compared with `--compare`'s file.
pub(super) struct Setting {
    pub(super) scene: String,
    pub(super) primary_only: bool,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) pattern: String,
    pub(super) max_depth: u32,
}

/// A measured row for the comparison: lanes, threads, new Mrays/s, and the old Mrays/s with how many old
/// rows it is the median of.
pub(super) type Compared = (LanesArg, usize, f64, Option<(f64, usize)>);

/// Notes (with `--json`) or the table comparing `compared` with `old`'s rows, and the old rows not measured.
pub(super) fn print(out: &mut impl Write, old: &Old, compared: Vec<Compared>, json: bool) -> Result<()> {
    let unmatched: Vec<String> = old
        .rows
        .keys()
        .filter(|&&(l, t)| !compared.iter().any(|&(cl, ct, ..)| (cl, ct) == (l, t)))
        .map(|(l, t)| format!("lanes {l} threads {t}"))
        .collect();
    if json {
        if !unmatched.is_empty() {
            eprintln!("note: rows of {} not measured now: {}", old.path.display(), unmatched.join(", "));
        }
        return Ok(());
    }
    writeln!(
        out,
        "\ncompared with {} (Mrays/s; old: the median when it holds several runs):",
        old.path.display()
    )?;
    writeln!(out, " lanes threads        old        new   new/old")?;
    for (lanes, t, new, old_mrays) in compared {
        match old_mrays {
            Some((m, n)) => writeln!(
                out,
                "{lanes:>6} {t:7} {m:10.2} {new:10.2} {:>8.3}x{}",
                new / m,
                if n > 1 { format!("  (old: median of {n})") } else { String::new() }
            )?,
            None => writeln!(out, "{lanes:>6} {t:7} {:>10} {new:10.2} {:>9}  no old row", "-", "-")?,
        }
    }
    if !unmatched.is_empty() {
        writeln!(out, "old rows not measured now: {}", unmatched.join(", "))?;
    }
    Ok(())
}
