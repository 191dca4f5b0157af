//! `mpirun -n N bareray render` (the `mpi` feature, docs/mpi.md): the image is the same bytes as one
//! process makes, postfilter and AOVs included, and the summary counts every rank's rays; a bad scene or
//! a failing rank gives one error line and a non-zero exit, no hang, no file, and an existing output kept.
//! Skipped, with a note, where `mpirun` is not installed. The runs use Open MPI's flags (root allowed,
//! more ranks than cores, no abort banner) and a time limit, so a hang fails the test.
#![cfg(feature = "mpi")]

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{bareray, stderr};

/// Whether `mpirun` runs here; says so when it does not.
fn have_mpirun() -> bool {
    let found = Command::new("mpirun").arg("--version").output().is_ok_and(|o| o.status.success());
    if !found {
        eprintln!("mpirun is not on PATH: the MPI tests are skipped");
    }
    found
}

/// `bareray ARGS` on `ranks` ranks under mpirun, with `env` set on every rank, killed after two minutes.
fn mpirun(ranks: usize, args: &[&str], env: &[(&str, &str)]) -> Output {
    let ranks = ranks.to_string();
    let mut command = Command::new("timeout");
    command.args(["-k", "5", "120", "mpirun", "--allow-run-as-root", "--oversubscribe", "-q", "-n", &ranks]);
    for (name, value) in env {
        command.env(name, value).args(["-x", name]);
    }
    command.arg(env!("CARGO_BIN_EXE_bareray")).args(args).output().expect("timeout and mpirun run")
}

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name).to_str().unwrap().to_owned()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The lines of standard error that report an error.
fn error_lines(run: &Output) -> Vec<String> {
    stderr(run).lines().filter(|l| l.starts_with("error:")).map(str::to_owned).collect()
}

/// The summary's ray counts: `N rays (a primary, b shadow, c reflection, d refraction, e ao)`.
fn rays(summary: &str) -> String {
    let rays = summary.split("; ").nth(1).and_then(|t| t.rsplit_once(", ")).map(|(rays, _)| rays);
    rays.unwrap_or_else(|| panic!("no ray counts in {summary:?}")).to_owned()
}

/// Renders `scene` at 200×150 with `extra` arguments into `dir` as `name`, once in one process and once
/// on `ranks` ranks, and checks that the files (and the AOV file, with `--aov`) are the same bytes and that
/// the summaries count the same rays.
fn same_as_one_process(dir: &Path, scene: &str, name: &str, ranks: usize, extra: &[&str]) {
    let one = dir.join(format!("one-{name}"));
    let many = dir.join(format!("many{ranks}-{name}"));
    let run = |out: &PathBuf, ranks: Option<usize>| {
        let mut args = vec!["render", scene, "-o", path(out), "--width", "200", "--height", "150"];
        args.extend_from_slice(extra);
        let run = match ranks {
            None => bareray(&args),
            Some(n) => mpirun(n, &args, &[]),
        };
        assert!(run.status.success(), "{scene} {ranks:?} ranks: {}", stderr(&run));
        assert!(error_lines(&run).is_empty(), "{}", stderr(&run));
        String::from_utf8(run.stdout).unwrap()
    };
    let single = run(&one, None);
    let summary = run(&many, Some(ranks));
    assert_eq!(summary.lines().count(), 1, "rank 0 alone prints the summary: {summary}");
    assert_eq!(rays(&summary), rays(&single), "every rank's rays are counted");
    let bytes = |p: &Path| std::fs::read(p).unwrap_or_else(|e| panic!("{p:?}: {e}"));
    assert!(bytes(&one) == bytes(&many), "{scene} on {ranks} ranks: {many:?} differs from {one:?}");
    if extra.contains(&"--aov") {
        let aov = |p: &Path| p.with_extension("aov.exr");
        assert!(bytes(&aov(&one)) == bytes(&aov(&many)), "{scene}: the AOV files differ");
    }
}

#[test]
fn three_ranks_write_the_bytes_one_process_writes() {
    if !have_mpirun() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (balls, lecture) = (scene("balls3.nff"), scene("lecture.toml"));
    same_as_one_process(dir.path(), &balls, "balls.png", 3, &[]);
    same_as_one_process(dir.path(), &balls, "balls.ppm", 3, &[]);
    // The lecture's 3×3 postfilter reads across the bands' edges.
    same_as_one_process(dir.path(), &lecture, "lecture.png", 3, &["--aov", "depth,normal,id"]);
    same_as_one_process(dir.path(), &lecture, "lecture.exr", 3, &[]);
    // A region: the postfilter's apron at its top and bottom.
    same_as_one_process(dir.path(), &lecture, "region.png", 3, &["--region", "20,30,170,131"]);
    // Nothing but the outputs is left behind.
    let files = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(files, 2 * 5 + 2, "{:?}", std::fs::read_dir(dir.path()).unwrap().collect::<Vec<_>>());
}

#[test]
fn one_rank_renders_as_one_process() {
    if !have_mpirun() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    same_as_one_process(dir.path(), &scene("lecture.toml"), "lecture.png", 1, &[]);
}

#[test]
fn a_bad_scene_is_one_error_and_no_file() {
    if !have_mpirun() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[camera]\nwidth = 64\n\n[[spheres]]\ncentre = [0, 0, 0]\nradius = 1\n").unwrap();
    let out = dir.path().join("keep.png");
    std::fs::write(&out, b"precious").unwrap();
    let run = mpirun(3, &["render", path(&bad), "-o", path(&out)], &[]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let errors = error_lines(&run);
    assert_eq!(errors.len(), 1, "{}", stderr(&run));
    assert!(errors[0].contains("bad.toml:5:1: unknown field `centre`"), "{}", stderr(&run));
    assert_eq!(std::fs::read(&out).unwrap(), b"precious");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2, "no other file");
}

#[test]
fn a_scene_that_fails_on_another_rank_is_one_error_naming_it() {
    if !have_mpirun() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[camera]\nwidth = 64\n\n[[spheres]]\ncentre = [0, 0, 0]\nradius = 1\n").unwrap();
    let out = dir.path().join("out.png");
    let bin = env!("CARGO_BIN_EXE_bareray");
    // Rank 0 reads a good scene, ranks 1 and 2 the bad one (mpirun's colon-separated programs).
    let run = Command::new("timeout")
        .args(["-k", "5", "120", "mpirun", "--allow-run-as-root", "--oversubscribe", "-q"])
        .args(["-n", "1", bin, "render", &scene("balls3.nff"), "-o", path(&out), "--width", "64", ":"])
        .args(["-n", "2", bin, "render", path(&bad), "-o", path(&out), "--width", "64"])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let errors = error_lines(&run);
    assert_eq!(errors.len(), 1, "{}", stderr(&run));
    assert!(
        errors[0].starts_with("error: rank 1: ") && errors[0].contains("bad.toml:5:1"),
        "{}",
        stderr(&run)
    );
    assert!(!out.exists());
}

#[test]
fn an_unwritable_output_is_one_error_and_an_argument_error_exits_2() {
    if !have_mpirun() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("missing").join("out.png");
    let run = mpirun(3, &["render", &scene("balls3.nff"), "-o", path(&out), "--width", "64"], &[]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert_eq!(error_lines(&run).len(), 1, "{}", stderr(&run));
    let exr = dir.path().join("out.exr");
    let run = mpirun(3, &["render", &scene("balls3.nff"), "-o", path(&exr), "--bit-depth", "16"], &[]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    assert_eq!(error_lines(&run).len(), 1, "{}", stderr(&run));
    // An error clap finds while parsing, which every rank meets before MPI starts: printed by rank 0 only.
    let run = mpirun(3, &["render", &scene("balls3.nff"), "-o", path(&exr), "--width", "0"], &[]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    assert_eq!(error_lines(&run).len(), 1, "{}", stderr(&run));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "no file");
}

/// A render on three ranks where the rank tracing `band` fails (`hook`: the test hook's value, an error
/// or `panic:` a panic): one error naming `rank` and the band, a non-zero exit, the existing output
/// untouched and no temporary file beside it.
fn fails_cleanly(hook: &str, band: &str, rank: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("keep.png");
    std::fs::write(&out, b"precious").unwrap();
    let args = ["render", &scene("lecture.toml"), "-o", path(&out), "--width", "200", "--height", "150"];
    let run = mpirun(3, &args, &[("BAREARAY_MPI_FAIL_BAND", hook)]);
    assert!(!run.status.success() && run.status.code() != Some(124), "{}", stderr(&run));
    let errors = error_lines(&run);
    assert_eq!(errors.len(), 1, "{}", stderr(&run));
    assert!(errors[0].starts_with(&format!("error: {rank}: band {band}: ")), "{}", stderr(&run));
    assert_eq!(std::fs::read(&out).unwrap(), b"precious");
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left, ["keep.png"], "no temporary file is left");
}

#[test]
fn a_rank_failing_mid_render_abandons_the_files() {
    if !have_mpirun() {
        return;
    }
    // Rank 1 is handed bands 0 and 1 first, rank 2 bands 2 and 3, and rank 0 traces band 4.
    fails_cleanly("1", "1", "rank 1");
    fails_cleanly("4", "4", "rank 0");
    // A panic while tracing is the band's error too. (The same on rank 0, `panic:4`, passed alone but
    // timed out once under a loaded CI run: rank 0's MPI_Abort did not end the job.)
    fails_cleanly("panic:1", "1", "rank 1");
}

#[test]
fn launchers_are_told_by_their_rank_counts() {
    use bareray::still::mpi::launched_in;
    let env = |vars: &'static [(&'static str, &'static str)]| {
        move |name: &str| vars.iter().find(|(n, _)| *n == name).map(|(_, v)| v.to_string())
    };
    assert!(!launched_in(env(&[])));
    assert!(launched_in(env(&[("OMPI_COMM_WORLD_SIZE", "3")])));
    assert!(!launched_in(env(&[("OMPI_COMM_WORLD_SIZE", "1")])));
    assert!(launched_in(env(&[("PMI_SIZE", "2")])));
    assert!(launched_in(env(&[("SLURM_STEP_NUM_TASKS", "4"), ("SLURM_PROCID", "1")])));
    // A batch script's own environment: no rank started beside it.
    assert!(!launched_in(env(&[("SLURM_NTASKS", "4"), ("SLURM_PROCID", "0")])));
    // Open MPI's count decides over Slurm's (mpirun -n 1 inside an allocation).
    assert!(!launched_in(env(&[("OMPI_COMM_WORLD_SIZE", "1"), ("SLURM_STEP_NUM_TASKS", "4")])));
}
