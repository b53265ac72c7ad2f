//! End-to-end tests of `pge preview --screenshot`: the real window, under Xvfb with Mesa's
//! software renderer (`.ci/preview-deps` installs both).
//!
//! Without an X server (no `Xvfb`, no `DISPLAY`) the tests print why and pass, unless the
//! `CI` variable is set (`.ci/run` sets `CI=true`): in CI they must run, and fail loudly when
//! they cannot.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// One window at a time (software rendering is slow enough with one).
static DISPLAY_LOCK: Mutex<()> = Mutex::new(());

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
}

/// An Xvfb server started for one test, stopped when dropped. The server picks a free
/// display itself (`-displayfd`), so no wrapper script and no display-number race.
struct Xvfb {
    child: std::process::Child,
    display: String,
}

impl Xvfb {
    fn start() -> Result<Xvfb, String> {
        use std::io::BufRead;
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1280x1024x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .stdin(Stdio::null())
            .spawn()
            .map_err(|e| format!("cannot start Xvfb: {e}"))?;
        let mut line = String::new();
        let stdout = child.stdout.take().ok_or("Xvfb has no stdout")?;
        std::io::BufReader::new(stdout)
            .read_line(&mut line)
            .map_err(|e| format!("Xvfb did not report its display: {e}"))?;
        let number = line.trim();
        if number.is_empty() || !number.bytes().all(|b| b.is_ascii_digit()) {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("Xvfb reported no display number ({line:?})"));
        }
        Ok(Xvfb {
            display: format!(":{number}"),
            child,
        })
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The command that runs `pge` with a display (and the server it needs, if any), or why
/// there is none.
fn pge_with_display() -> Result<(Command, Option<Xvfb>), String> {
    let pge = env!("CARGO_BIN_EXE_pge");
    if on_path("Xvfb") {
        let server = Xvfb::start()?;
        let mut cmd = Command::new(pge);
        cmd.env("DISPLAY", &server.display);
        return Ok((cmd, Some(server)));
    }
    if std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty()) {
        return Ok((Command::new(pge), None));
    }
    Err("no X server: Xvfb is not installed and DISPLAY is not set (run .ci/preview-deps)".into())
}

/// Whether the tests run in CI (`CI` set to anything but empty, `0` or `false`, as CI
/// services and `.ci/run` set it): there a missing display fails the test instead of
/// skipping it.
fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !matches!(v.trim(), "" | "0" | "false"))
}

/// Runs `pge preview ARGS` with a display; `None` (after printing why) when the test must be
/// skipped.
fn preview(args: &[&str], dir: &Path) -> Option<Output> {
    let _guard = DISPLAY_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let (mut cmd, _server) = match pge_with_display() {
        Ok(found) => found,
        Err(why) if !in_ci() => {
            eprintln!("skipping the preview window test: {why}");
            return None;
        }
        Err(why) => panic!("CI is set but the preview cannot run: {why}"),
    };
    cmd.arg("preview").args(args).current_dir(dir);
    cmd.stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .stdin(Stdio::null());
    let mut child = cmd.spawn().expect("start pge preview");
    let end = Instant::now() + Duration::from_secs(300);
    loop {
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        if Instant::now() > end {
            let _ = child.kill();
            panic!("pge preview {args:?} did not finish in 300 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    Some(child.wait_with_output().expect("output"))
}

/// Pixel counts of a screenshot, right of the side panel (the viewport).
struct Picture {
    width: u32,
    height: u32,
    /// Distinct clearly coloured (not grey) values in the viewport.
    colours: usize,
    bluish: usize,
    reddish: usize,
}

fn look_at(png: &Path) -> Picture {
    let img = image::open(png).expect("a PNG").to_rgba8();
    let (width, height) = img.dimensions();
    let mut colours = std::collections::HashSet::new();
    let (mut bluish, mut reddish) = (0, 0);
    for (x, _, p) in img.enumerate_pixels() {
        let [r, g, b, _] = p.0.map(i32::from);
        if x < width / 4 {
            continue;
        }
        if r.max(g).max(b) - r.min(g).min(b) > 30 {
            colours.insert(p.0);
        }
        if b > r + 40 && b > g + 15 {
            bluish += 1;
        }
        if r > b + 40 && r > g + 15 {
            reddish += 1;
        }
    }
    Picture {
        width,
        height,
        colours: colours.len(),
        bluish,
        reddish,
    }
}

#[test]
fn screenshot_of_an_example_shows_the_model() {
    let dir = tempfile::tempdir().expect("tempdir");
    let png = dir.path().join("spiral.png");
    let script = root().join("scripts/examples/spiral.lua");
    let Some(out) = preview(
        &[
            script.to_str().expect("utf-8 path"),
            "--screenshot",
            png.to_str().expect("utf-8 path"),
        ],
        dir.path(),
    ) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "pge preview failed: {stderr}");
    let pic = look_at(&png);
    assert!(
        pic.width >= 640 && pic.height >= 400,
        "{}x{}",
        pic.width,
        pic.height
    );
    assert!(
        pic.colours > 50,
        "a lit model has many shades, this one {}",
        pic.colours
    );
    // The spiral's boxes go from blue at the bottom to orange at the top: both must fill a
    // good part of the viewport (the red and blue axis lines alone are a few hundred pixels).
    assert!(pic.bluish > 5000, "blue boxes: {} pixels", pic.bluish);
    assert!(pic.reddish > 5000, "orange boxes: {} pixels", pic.reddish);
}

#[test]
fn a_script_error_is_shown_and_fails_the_screenshot_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("broken.lua"),
        "local x = 1\nlocal y = = 2\nreturn x\n",
    )
    .expect("write");
    let Some(out) = preview(&["broken.lua", "--screenshot", "broken.png"], dir.path()) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(stderr.contains("broken.lua:2:"), "FILE:LINE in: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // The window still showed the error: the picture was taken.
    let pic = look_at(&dir.path().join("broken.png"));
    assert!(
        pic.reddish > 200,
        "the error banner is red: {} pixels",
        pic.reddish
    );
}

#[test]
fn a_missing_script_is_reported_as_gone() {
    let dir = tempfile::tempdir().expect("tempdir");
    let Some(out) = preview(&["nothing.lua", "--screenshot", "nothing.png"], dir.path()) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(stderr.contains("nothing.lua: file is gone"), "{stderr}");
}

#[test]
fn a_script_that_runs_forever_is_stopped_by_the_time_limit() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("forever.lua"),
        "local n = 0\nwhile true do n = n + 1 end\n",
    )
    .expect("write");
    let Some(out) = preview(
        &[
            "forever.lua",
            "--time-limit",
            "1",
            "--screenshot",
            "forever.png",
        ],
        dir.path(),
    ) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(stderr.contains("forever.lua:2:"), "{stderr}");
    assert!(stderr.contains("time limit"), "{stderr}");
}

#[test]
fn an_environment_is_the_viewport_background() {
    let dir = tempfile::tempdir().expect("tempdir");
    let png = dir.path().join("environment.png");
    let script = root().join("tests/scripts/environment.lua");
    let Some(out) = preview(
        &[
            script.to_str().expect("utf-8 path"),
            "--screenshot",
            png.to_str().expect("utf-8 path"),
        ],
        dir.path(),
    ) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "pge preview failed: {stderr}");
    let img = image::open(&png).expect("a PNG").to_rgba8();
    let (width, height) = img.dimensions();
    // The fraction of a band of viewport rows (right of the side panel) whose pixels pass.
    let band = |rows: std::ops::Range<u32>, test: &dyn Fn([i32; 4]) -> bool| {
        let (mut hits, mut all) = (0usize, 0usize);
        for y in rows {
            for x in (width * 3 / 8)..width {
                all += 1;
                if test(img.get_pixel(x, y).0.map(i32::from)) {
                    hits += 1;
                }
            }
        }
        hits as f64 / all.max(1) as f64
    };
    // The camera looks slightly down: above the model is the script's blue sky, below it
    // the brown ground half of the image (the plain background is a dark grey).
    let sky = band(height / 20..height / 8, &|[r, g, b, _]| {
        b > 200 && b > r + 60 && b > g + 20
    });
    let ground = band(height * 15 / 16..height, &|[r, g, b, _]| {
        r > b + 25 && r > g && (60..160).contains(&r)
    });
    assert!(sky > 0.9, "sky blue on top: {:.0} %", sky * 100.0);
    assert!(
        ground > 0.6,
        "brown ground at the bottom: {:.0} %",
        ground * 100.0
    );
}

/// The triangles and forest leaves a screenshot run reports drawing.
fn drawn(stdout: &[u8]) -> (u64, u64) {
    let text = String::from_utf8_lossy(stdout);
    let line = text
        .lines()
        .find(|l| l.contains("triangles drawn"))
        .unwrap_or_else(|| panic!("no 'triangles drawn' line in: {text}"));
    let numbers: Vec<u64> = line
        .split(|c: char| !c.is_ascii_digit())
        .filter_map(|w| w.parse().ok())
        .collect();
    match numbers[..] {
        [.., triangles, leaves] => (triangles, leaves),
        _ => panic!("no counts in {line:?}"),
    }
}

/// A directory with `small.lua`: about 170 bushes of two variants on a 40 m terrain.
fn small_forest() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::copy(
        root().join("scripts/species/bush.lua"),
        dir.path().join("bush.lua"),
    )
    .expect("copy the species");
    std::fs::write(
        dir.path().join("small.lua"),
        "local f = pge.Forest{ size = {40, 40}, seed = 3 }\n\
         f:terrain{ height = 2, scale = 30, octaves = 2 }\n\
         f:scatter{ species = \"bush.lua\", minDistance = 3, variants = 2,\n\
                    params = { points = 300 } }\n\
         return f\n",
    )
    .expect("write");
    dir
}

#[test]
fn a_forest_is_drawn_within_its_leaf_budget() {
    let dir = small_forest();
    let shot = |budget: &str, png: &str| {
        let out = preview(
            &[
                "small.lua",
                "--leaf-budget",
                budget,
                "--camera",
                "30,12",
                "--screenshot",
                png,
            ],
            dir.path(),
        )?;
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "pge preview failed: {stderr}");
        Some((drawn(&out.stdout), look_at(&dir.path().join(png))))
    };
    let Some(((all_triangles, all_leaves), all)) = shot("100000000", "all.png") else {
        return;
    };
    let Some(((triangles, leaves), tight)) = shot("3000", "tight.png") else {
        return;
    };
    // About 170 bushes of 400 to 500 leaves: a generous budget draws them all whole, a
    // tight one at most its 3000 leaves (and as many triangles of bark), yet every bush in
    // view still has some.
    assert!(all_leaves > 20_000, "all the leaves: {all_leaves}");
    assert!(
        (1_000..=3_000).contains(&leaves),
        "{leaves} leaves drawn for a budget of 3000"
    );
    assert!(
        triangles < all_triangles / 5,
        "{triangles} of {all_triangles} triangles"
    );
    assert!(
        all.colours > 50 && tight.colours > 50,
        "lit leaves and bark"
    );
}

#[test]
fn an_orbit_reports_every_frame_and_ends_on_the_resting_plan() {
    let dir = small_forest();
    let Some(out) = preview(
        &[
            "small.lua",
            "--leaf-budget",
            "3000",
            "--camera",
            "30,12",
            "--orbit-frames",
            "4",
            "--screenshot",
            "orbit.png",
        ],
        dir.path(),
    ) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "pge preview failed: {stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    let moving: Vec<&&str> = lines
        .iter()
        .filter(|l| l.starts_with("orbit frame") && l.contains("moving"))
        .collect();
    assert_eq!(moving.len(), 4, "{stderr}");
    for (k, line) in moving.iter().enumerate() {
        assert!(
            line.starts_with(&format!("orbit frame {}/4 moving: plan ", k + 1)),
            "{line}"
        );
        for part in ["upload", "submit", "gpu", "render"] {
            assert!(line.contains(part), "{part} missing in {line}");
        }
    }
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("orbit frame 4/4 resting")),
        "{stderr}"
    );
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("orbit: ") && l.contains("while turning (4 frames)")),
        "{stderr}"
    );
    // The picture is of the resting frame with its own plan: the budget's leaves, not the
    // 128th of it a moving frame draws.
    let (_, leaves) = drawn(&out.stdout);
    assert!(
        (1_000..=3_000).contains(&leaves),
        "{leaves} leaves drawn for a budget of 3000"
    );
    assert!(look_at(&dir.path().join("orbit.png")).colours > 50);
}

#[test]
fn an_orbit_of_a_failing_script_ends_with_its_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("broken.lua"),
        "local x = 1\nlocal y = = 2\nreturn x\n",
    )
    .expect("write");
    let Some(out) = preview(&["broken.lua", "--orbit-frames", "3"], dir.path()) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(stderr.contains("broken.lua:2:"), "FILE:LINE in: {stderr}");
    assert!(!stderr.contains("orbit frame"), "nothing turned: {stderr}");
}
