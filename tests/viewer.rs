//! The viewer's real window under Xvfb (with Mesa's lavapipe Vulkan), driven by xdotool:
//! keys and mouse move the camera, H toggles hard shadows, F12 and the overlay's button save
//! screenshots, `--frames`/`--screenshot` end a run with the final frame. The saved images are
//! checked: not blank, changed by camera moves, and sharper shadow edges with hard shadows.
//! With `--stats-file` the viewer reports each image it shows: input is answered within the
//! 100 ms budget (its own measurement, key event to present), images keep coming while a key
//! is held, the automatic exposure holds while a room converges, and a view saved with V is
//! rendered exactly by `render --view`.
//!
//! Each test starts its own `Xvfb :N` and kills it at the end; without Xvfb (or xdotool for
//! the interactive test) the test prints why and passes, except under CI (`CI=true`), where it
//! fails. The tests run one at a time (the machine may have two cores).

mod common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant};

/// How long one step (a convergence, a screenshot) may take on a slow, shared machine.
const STEP_TIMEOUT: Duration = Duration::from_secs(120);

/// One viewer test at a time.
static SERIAL: Mutex<()> = Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

fn binary() -> String {
    std::env::var("PENUMBRA_TEST_BINARY")
        .unwrap_or_else(|_| env!("CARGO_BIN_EXE_penumbra").to_string())
}

fn test_device() -> String {
    std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "cpu".into())
}

/// A test that cannot run: it passes with a note, or under CI (`CI=true`) fails.
fn skip(why: &str) {
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{why}; CI=true, where every viewer test must run");
    }
    println!("SKIPPED: {why}");
}

/// Whether `tool` can be run.
fn have(tool: &str) -> bool {
    Command::new(tool)
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok()
}

/// A private X server, killed on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    /// Starts Xvfb on a free display number; `None` (with a message) when Xvfb is missing.
    fn start() -> Option<Xvfb> {
        if !have("Xvfb") {
            skip("Xvfb is not installed (apt-get install xvfb)");
            return None;
        }
        // Xvfb picks a free display itself and writes its number once it accepts connections
        // (-displayfd): tests starting at once can neither take the same number nor connect
        // before the server is up.
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1024x768x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb starts");
        let mut line = String::new();
        let stdout = child.stdout.take().expect("Xvfb's stdout is piped");
        let _ = BufReader::new(stdout).read_line(&mut line);
        let Ok(n) = line.trim().parse::<u32>() else {
            let _ = child.kill();
            panic!("Xvfb did not report a display number (it wrote {line:?})");
        };
        Some(Xvfb {
            child,
            display: format!(":{n}"),
        })
    }

    /// What the window `wid` shows, grabbed from the X server with ImageMagick's `import`.
    fn window_image(&self, wid: &str, dir: &Path) -> Gray {
        let png = dir.join(format!("window-{wid}.png"));
        let o = Command::new("import")
            .args(["-window", wid, png.to_str().unwrap()])
            .env("DISPLAY", &self.display)
            .output()
            .expect("ImageMagick's import runs");
        assert!(
            o.status.success(),
            "import failed: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        load(&png)
    }

    /// Runs xdotool on this display; returns its stdout.
    fn xdotool(&self, args: &[&str]) -> String {
        let o = Command::new("xdotool")
            .args(args)
            .env("DISPLAY", &self.display)
            .output()
            .expect("xdotool runs");
        assert!(
            o.status.success(),
            "xdotool {args:?} failed: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    }

    /// The viewer's window id (its title starts with "penumbra").
    fn find_window(&self) -> String {
        let start = Instant::now();
        loop {
            let o = Command::new("xdotool")
                .args(["search", "--name", "^penumbra"])
                .env("DISPLAY", &self.display)
                .output()
                .expect("xdotool runs");
            let out = String::from_utf8_lossy(&o.stdout);
            if let Some(id) = out.lines().next().filter(|l| !l.trim().is_empty()) {
                return id.trim().to_string();
            }
            assert!(
                start.elapsed() < STEP_TIMEOUT,
                "no window titled penumbra appeared"
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The viewer's command line on `x`'s display in `dir`.
fn viewer_command(x: &Xvfb, dir: &Path, args: &[&str]) -> Command {
    let mut c = Command::new(binary());
    c.args(args)
        .current_dir(dir)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("PENUMBRA_DEVICE", test_device())
        // Quiet the windowing stack's warnings about Xvfb (no XSETTINGS, a 0 mm screen) and
        // Mesa's about a missing runtime folder.
        .env("RUST_LOG", "warn,winit=error,egui_wgpu=error")
        .env("XDG_RUNTIME_DIR", dir);
    c
}

/// A running viewer whose stdout lines arrive on a channel.
struct Viewer {
    child: Child,
    lines: Receiver<String>,
}

impl Viewer {
    fn spawn(mut command: Command) -> Viewer {
        let mut child = command
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("the viewer starts");
        let stdout = child.stdout.take().expect("stdout is piped");
        let (tx, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Viewer { child, lines }
    }

    /// The next stdout line containing `what`.
    fn wait_for(&mut self, what: &str) -> String {
        let deadline = Instant::now() + STEP_TIMEOUT;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) if line.contains(what) => return line,
                Ok(_) => {}
                Err(RecvTimeoutError::Timeout) => panic!("no '{what}' line from the viewer"),
                Err(RecvTimeoutError::Disconnected) => {
                    let status = self.child.wait().ok();
                    panic!("the viewer exited ({status:?}) before printing '{what}'")
                }
            }
        }
    }

    /// Waits for the screenshot line and returns the PNG path (relative to `dir`).
    fn screenshot_path(&mut self, dir: &Path) -> PathBuf {
        let line = self.wait_for("saved ");
        let png = line
            .split("saved ")
            .nth(1)
            .and_then(|rest| rest.split(" and ").next())
            .unwrap_or_else(|| panic!("unexpected line: {line}"));
        let path = dir.join(png);
        assert!(path.exists(), "{} is missing", path.display());
        assert!(
            path.with_extension("exr").exists(),
            "the EXR beside {} is missing",
            path.display()
        );
        path
    }

    fn wait_exit(&mut self) -> ExitStatus {
        let start = Instant::now();
        loop {
            if let Some(s) = self.child.try_wait().expect("the viewer can be waited for") {
                return s;
            }
            assert!(start.elapsed() < STEP_TIMEOUT, "the viewer did not exit");
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// A PNG as luminance in [0, 1], with its size.
struct Gray {
    width: usize,
    height: usize,
    pixels: Vec<f32>,
}

fn load(path: &Path) -> Gray {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    let pixels = img
        .pixels()
        .map(|p| (0.2126 * p[0] as f32 + 0.7152 * p[1] as f32 + 0.0722 * p[2] as f32) / 255.0)
        .collect();
    Gray {
        width: img.width() as usize,
        height: img.height() as usize,
        pixels,
    }
}

impl Gray {
    fn at(&self, x: usize, y: usize) -> f32 {
        self.pixels[y * self.width + x]
    }

    /// Asserts the image shows something: neither flat nor black nor white.
    fn assert_not_blank(&self, what: &str) {
        let n = self.pixels.len() as f32;
        let mean = self.pixels.iter().sum::<f32>() / n;
        let var = self.pixels.iter().map(|p| (p - mean).powi(2)).sum::<f32>() / n;
        assert!(
            (0.03..0.97).contains(&mean) && var.sqrt() > 0.05,
            "{what} looks blank: mean {mean}, deviation {}",
            var.sqrt()
        );
    }

    /// Means over `block`×`block` tiles (averages noise out, keeps the picture).
    fn blocks(&self, block: usize) -> Vec<f32> {
        let (bw, bh) = (self.width / block, self.height / block);
        let mut out = Vec::with_capacity(bw * bh);
        for by in 0..bh {
            for bx in 0..bw {
                let mut sum = 0.0;
                for y in by * block..(by + 1) * block {
                    for x in bx * block..(bx + 1) * block {
                        sum += self.at(x, y);
                    }
                }
                out.push(sum / (block * block) as f32);
            }
        }
        out
    }

    /// Sharpness of the shadow edge that the bundled Cornell box's tall block casts from the
    /// point light onto the back wall (a diagonal edge in the region below, given in fractions
    /// of the image so any size works). The edge is located in each column (largest step of a
    /// lightly smoothed profile), a line is fitted through those points, and the luminance
    /// profile across the line is averaged along it (edge-spread function; the averaging
    /// over ~50 columns quiets the noise). The result is the profile's steepest one-pixel step
    /// over its whole contrast: about 1/3 for a hard edge, well under that for a penumbra.
    fn edge_sharpness(&self) -> f32 {
        let x0 = (0.53 * self.width as f32) as usize;
        let x1 = (0.68 * self.width as f32) as usize;
        let y0 = (0.47 * self.height as f32) as usize;
        let y1 = (0.61 * self.height as f32) as usize;
        let smooth = |x: usize, y: usize| {
            let mut s = 0.0;
            for dx in 0..3 {
                for dy in 0..2 {
                    s += self.at(x + dx - 1, y + dy);
                }
            }
            s / 6.0
        };
        // Locate the edge in each column and fit y = a + b·x through it.
        let points: Vec<(f32, f32)> = (x0..x1)
            .map(|x| {
                let step = |y: &usize| (smooth(x, y + 2) - smooth(x, *y)).abs();
                let y = (y0..y1)
                    .max_by(|a, b| step(a).total_cmp(&step(b)))
                    .unwrap_or(y0);
                (x as f32, y as f32 + 1.5)
            })
            .collect();
        let n = points.len() as f32;
        let (mx, my) = points
            .iter()
            .fold((0.0, 0.0), |(sx, sy), (x, y)| (sx + x / n, sy + y / n));
        let sxy: f32 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
        let sxx: f32 = points.iter().map(|(x, _)| (x - mx).powi(2)).sum();
        let b = sxy / sxx;
        let a = my - b * mx;
        // The profile across the line, averaged along it.
        let sample = |x: usize, y: f32| {
            let (yi, f) = (y.floor() as usize, y - y.floor());
            self.at(x, yi) * (1.0 - f) + self.at(x, yi + 1) * f
        };
        let profile: Vec<f32> = (-8..=8)
            .map(|d| {
                (x0..x1)
                    .map(|x| sample(x, a + b * x as f32 + d as f32))
                    .sum::<f32>()
                    / n
            })
            .collect();
        let (lo, hi) = profile
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let steepest = profile
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f32::max);
        steepest / (hi - lo).max(1e-6)
    }
}

/// Mean absolute difference of two images' 8×8 block means.
fn picture_difference(a: &Gray, b: &Gray) -> f32 {
    assert_eq!((a.width, a.height), (b.width, b.height), "sizes differ");
    let (a, b) = (a.blocks(8), b.blocks(8));
    a.iter().zip(&b).map(|(p, q)| (p - q).abs()).sum::<f32>() / a.len() as f32
}

/// A PNG's width and height.
fn png_size(path: &Path) -> (u32, u32) {
    image::image_dimensions(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

impl Gray {
    /// The `w`×`h` part at (`x`, `y`).
    fn crop(&self, x: usize, y: usize, w: usize, h: usize) -> Gray {
        let pixels = (y..y + h)
            .flat_map(|r| self.pixels[r * self.width + x..][..w].iter().copied())
            .collect();
        Gray {
            width: w,
            height: h,
            pixels,
        }
    }

    /// Mean absolute difference per pixel.
    fn mean_abs_difference(&self, other: &Gray) -> f32 {
        assert_eq!((self.width, self.height), (other.width, other.height));
        let sum: f32 = self
            .pixels
            .iter()
            .zip(&other.pixels)
            .map(|(a, b)| (a - b).abs())
            .sum();
        sum / self.pixels.len() as f32
    }
}

/// Whether two PNGs hold the same pixels.
fn same_pixels(a: &Path, b: &Path) -> bool {
    let load = |p: &Path| image::open(p).expect("a PNG").to_rgba8().into_raw();
    load(a) == load(b)
}

fn run_to_exit(command: &mut Command) -> Output {
    command.output().expect("the viewer runs")
}

#[test]
fn without_a_display_the_viewer_points_to_render() {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(binary())
        .args(["view", "--frames", "1"])
        .current_dir(dir.path())
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "stderr: {stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.starts_with("penumbra: error:") && stderr.contains("penumbra render"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn frames_and_screenshot_save_the_final_frame_and_hard_shadows_are_sharper() {
    let _serial = serial();
    let Some(x) = Xvfb::start() else { return };
    let dir = tempfile::tempdir().unwrap();
    // Without the overlay the image is the whole window.
    let common = [
        "--width",
        "320",
        "--height",
        "240",
        "--bounces",
        "1",
        "--spp",
        "48",
        "--frames",
        "2",
        "--no-overlay",
        // A fixed exposure and tone curve: the edge is measured, not the automatic exposure.
        "--exposure",
        "1.2",
        "--tonemap",
        "aces",
    ];
    let mut shots = Vec::new();
    for (name, extra) in [("soft", None), ("hard", Some("--hard-shadows"))] {
        let png = dir.path().join(format!("{name}.png"));
        let mut args: Vec<&str> = common.to_vec();
        args.extend(extra);
        args.extend(["--screenshot", png.to_str().unwrap()]);
        let t = Instant::now();
        let o = run_to_exit(&mut viewer_command(&x, dir.path(), &args));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{name}: {}\n{stdout}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            stdout.contains("(320×240, 48 spp)"),
            "{name}: not converged: {stdout}"
        );
        println!("{name}: {:.1} s", t.elapsed().as_secs_f64());
        assert!(png.with_extension("exr").exists());
        let (w, h, _) = penumbra::image_io::read_exr(&png.with_extension("exr")).unwrap();
        assert_eq!((w, h), (320, 240));
        let img = load(&png);
        img.assert_not_blank(name);
        shots.push(img);
    }
    let (soft, hard) = (shots[0].edge_sharpness(), shots[1].edge_sharpness());
    println!("edge sharpness: soft {soft:.4}, hard {hard:.4}");
    assert!(
        hard > 1.8 * soft,
        "hard shadows should have sharper edges: soft {soft}, hard {hard}"
    );
}

#[test]
fn keys_and_mouse_drive_the_window() {
    let _serial = serial();
    if !have("xdotool") || !have("import") {
        skip("xdotool or ImageMagick is not installed (apt-get install xdotool imagemagick)");
        return;
    }
    let Some(x) = Xvfb::start() else { return };
    let dir = tempfile::tempdir().unwrap();
    let last = dir.path().join("last.png");
    let args = [
        "--width",
        "320",
        "--height",
        "240",
        "--bounces",
        "1",
        "--spp",
        "48",
        "--no-overlay",
        // As above: the edge is measured under a fixed exposure and tone curve.
        "--exposure",
        "1.2",
        "--tonemap",
        "aces",
        "--screenshot",
        last.to_str().unwrap(),
    ];
    let mut v = Viewer::spawn(viewer_command(&x, dir.path(), &args));
    let t = Instant::now();
    let wid = x.find_window();
    let title = x.xdotool(&["getwindowname", &wid]);
    assert!(title.starts_with("penumbra"), "title: {title}");
    // Without a window manager, keys reach the window only once it has the focus.
    x.xdotool(&["windowfocus", "--sync", &wid]);
    v.wait_for("reached 48 spp");
    println!(
        "first frame converged after {:.1} s",
        t.elapsed().as_secs_f64()
    );

    // The overlay is hidden (--no-overlay): the image fills the window; F12 saves exactly it.
    x.xdotool(&["key", "F12"]);
    let soft = v.screenshot_path(dir.path());
    load(&soft).assert_not_blank("the first screenshot");
    assert_eq!(png_size(&soft), (320, 240));

    // H switches to hard shadows: the accumulation restarts and the edges sharpen.
    x.xdotool(&["key", "h"]);
    v.wait_for("reached 48 spp");
    x.xdotool(&["key", "F12"]);
    let hard = v.screenshot_path(dir.path());
    assert_ne!(soft, hard, "screenshots must not overwrite each other");
    let (s, h) = (load(&soft).edge_sharpness(), load(&hard).edge_sharpness());
    println!("after H: edge sharpness soft {s:.4}, hard {h:.4}");
    assert!(h > 1.8 * s, "H did not sharpen the shadows: {s} -> {h}");

    // W moves the camera forward: the picture changes.
    x.xdotool(&["keydown", "w", "sleep", "0.4", "keyup", "w"]);
    v.wait_for("reached 48 spp");
    x.xdotool(&["key", "F12"]);
    let forward = v.screenshot_path(dir.path());
    let moved = picture_difference(&load(&hard), &load(&forward));
    println!("after W: picture difference {moved:.4}");
    assert!(moved > 0.02, "W did not move the camera ({moved})");

    // Dragging with the right button turns the view.
    x.xdotool(&["mousemove", "--window", &wid, "160", "120"]);
    x.xdotool(&["mousedown", "3"]);
    for dx in [20, 40, 60, 80] {
        x.xdotool(&[
            "mousemove",
            "--window",
            &wid,
            &(160 + dx).to_string(),
            "120",
        ]);
    }
    x.xdotool(&["mouseup", "3"]);
    v.wait_for("reached 48 spp");
    x.xdotool(&["key", "F12"]);
    let turned = v.screenshot_path(dir.path());
    let turn = picture_difference(&load(&forward), &load(&turned));
    println!("after the drag: picture difference {turn:.4}");
    assert!(turn > 0.02, "the mouse drag did not turn the view ({turn})");
    load(&turned).assert_not_blank("the turned view");

    // Tab shows the overlay: a side panel of fixed width, the image laid out beside it (the
    // film is re-rendered at the size of the rest of the window, so nothing is letterboxed).
    x.xdotool(&["key", "Tab"]);
    v.wait_for("reached 48 spp");
    // Its Screenshot button (top left of the panel) saves the image without the panel.
    x.xdotool(&["mousemove", "--window", &wid, "40", "11", "click", "1"]);
    let button = v.screenshot_path(dir.path());
    let (w, h) = png_size(&button);
    assert_eq!(h, 240);
    assert!(
        (100..240).contains(&w),
        "the image beside the panel is {w} wide"
    );
    // The window shows that image, unscaled and uncovered, right of the panel.
    let window = x.window_image(&wid, dir.path());
    let shown = window.crop(320 - w as usize, 0, w as usize, h as usize);
    let on_screen = shown.mean_abs_difference(&load(&button));
    println!("image beside the panel: {w}×{h}, differs from the PNG by {on_screen:.4}");
    assert!(
        on_screen < 0.01,
        "the window does not show the saved image beside the panel ({on_screen})"
    );
    x.xdotool(&["key", "F12"]);
    let key = v.screenshot_path(dir.path());
    assert_ne!(button, key, "screenshots must not overwrite each other");
    assert!(
        same_pixels(&button, &key),
        "the button's screenshot differs from F12's (overlay in the image?)"
    );

    // Ctrl+Q quits; --screenshot saves the final frame on the way out.
    x.xdotool(&["key", "ctrl+q"]);
    let status = v.wait_exit();
    assert!(status.success(), "exit status {status}");
    assert!(last.exists() && last.with_extension("exr").exists());
    assert!(same_pixels(&last, &key), "the final frame differs");
    println!("total {:.1} s", t.elapsed().as_secs_f64());
}

/// A closed room 6 × 2.7 × 4 m (faces inward) with a point light below the ceiling and no
/// camera: the first view stands inside it (an interior: collision on, exposure metered on the
/// image).
fn room(dir: &Path) -> PathBuf {
    let mut g = common::Gltf::default();
    let white = g.lambert([0.7; 3], [0.0; 3], 1.0, false);
    let (positions, outward) = common::cuboid([-3.0, 0.0, -2.0], [3.0, 2.7, 2.0]);
    let indices: Vec<u32> = outward.chunks(3).flat_map(|t| [t[0], t[2], t[1]]).collect();
    let table = common::cuboid([-0.6, 0.0, -0.9], [0.6, 0.8, -0.2]);
    let mesh = g.mesh(vec![
        common::Prim::triangles(positions, indices, white),
        common::Prim::triangles(table.0, table.1, white),
    ]);
    g.node(serde_json::json!({"mesh": mesh}));
    g.lights
        .push(serde_json::json!({"type": "point", "intensity": 30.0}));
    g.node(
        serde_json::json!({"extensions": {"KHR_lights_punctual": {"light": 0}},
        "translation": [0.5, 2.4, 0.3]}),
    );
    g.write_glb(dir, "room")
}

/// A test driving the window: the one-at-a-time lock, a private X server, and the test's output
/// folder; `None` (skipped, with the reason) without Xvfb or xdotool.
fn interactive(name: &str) -> Option<(std::sync::MutexGuard<'static, ()>, Xvfb, PathBuf)> {
    let lock = serial();
    let x = Xvfb::start()?;
    if !have("xdotool") {
        skip("xdotool is not installed");
        return None;
    }
    Some((lock, x, common::output_dir(name)))
}

/// The `--stats-file` lines written so far (one per image shown).
fn stats_lines(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect()
}

/// Waits until the stats file holds a line that `done` accepts.
fn wait_for_image(path: &Path, what: &str, done: impl Fn(&serde_json::Value) -> bool) {
    let start = Instant::now();
    while !stats_lines(path).iter().any(&done) {
        assert!(start.elapsed() < STEP_TIMEOUT, "no image: {what}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn input_is_answered_within_the_budget_and_moving_never_freezes_the_image() {
    // The viewer measures each input's latency itself: from the key's X event to the present
    // of the first image rendered after it (the `latency_ms` of --stats-file). On the 2-core
    // CPU a full-size sample of a room takes far longer than 100 ms; the preview must still
    // answer within the 100 ms the issue asks for.
    let Some((_serial, x, dir)) = interactive("viewer_latency") else {
        return;
    };
    let room = room(&dir);
    for scene in [None, Some(room)] {
        let stats = dir.join("stats.jsonl");
        let _ = std::fs::remove_file(&stats);
        let mut args = vec!["view".to_string()];
        args.extend(scene.iter().map(|p| p.display().to_string()));
        args.extend(["--stats-file".into(), stats.display().to_string()]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let _viewer = Viewer::spawn(viewer_command(&x, &dir, &args));
        wait_for_image(&stats, "the first image", |_| true);
        let wid = x.find_window();
        x.xdotool(&["windowfocus", "--sync", &wid]);
        // At rest the preview climbs back to full quality, in bands of a sample.
        wait_for_image(&stats, "full resolution", |l| l["divisor"] == 1);
        for _ in 0..4 {
            x.xdotool(&["keydown", "d"]);
            std::thread::sleep(Duration::from_millis(150));
            x.xdotool(&["keyup", "d"]);
            std::thread::sleep(Duration::from_millis(1500));
        }
        // Held for two seconds: images keep coming.
        let held_from = stats_lines(&stats).len();
        x.xdotool(&["keydown", "a"]);
        std::thread::sleep(Duration::from_secs(2));
        x.xdotool(&["keyup", "a"]);
        std::thread::sleep(Duration::from_millis(300));
        let lines = stats_lines(&stats);
        let latencies: Vec<f64> = lines
            .iter()
            .filter_map(|l| l["latency_ms"].as_f64())
            .collect();
        assert!(
            latencies.len() >= 4,
            "{scene:?}: the key presses were not answered: {latencies:?}"
        );
        let mut sorted = latencies.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        assert!(
            median <= 100.0,
            "{scene:?}: input answered in {latencies:?} ms (median {median:.0})"
        );
        let times: Vec<f64> = lines[held_from..]
            .iter()
            .map(|l| l["t"].as_f64().unwrap())
            .collect();
        assert!(
            times.len() >= 10,
            "{scene:?}: {} images in 2 s of moving",
            times.len()
        );
        let gap = times.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
        assert!(
            gap < 0.5,
            "{scene:?}: the image froze for {gap:.2} s while moving"
        );
    }
}

#[test]
fn exposure_holds_while_the_image_converges() {
    // A room's automatic exposure is decided from its first full image and held: the drift of
    // the issue (−0.7 → −2.3 stops over a minute in an apartment) would show here as the
    // samples grow sixteenfold.
    let _serial = serial();
    let Some(x) = Xvfb::start() else { return };
    let dir = common::output_dir("viewer_exposure");
    let room = room(&dir);
    let stats = dir.join("stats.jsonl");
    let _viewer = Viewer::spawn(viewer_command(
        &x,
        &dir,
        &[
            "view",
            room.to_str().unwrap(),
            "--width",
            "400",
            "--height",
            "300",
            "--no-overlay",
            "--stats-file",
            stats.to_str().unwrap(),
        ],
    ));
    wait_for_image(&stats, "16 spp at full resolution", |l| {
        l["divisor"] == 1 && l["spp"].as_u64().unwrap_or(0) >= 16
    });
    let full: Vec<_> = stats_lines(&stats)
        .into_iter()
        .filter(|l| l["divisor"] == 1)
        .collect();
    assert!(full.len() >= 3, "{full:?}");
    let exposures: Vec<f64> = full
        .iter()
        .map(|l| l["exposure"].as_f64().unwrap())
        .collect();
    assert!(
        exposures.iter().all(|&e| e == exposures[0]),
        "the exposure moved while converging: {exposures:?}"
    );
}

#[test]
fn a_saved_view_is_restored_exactly_by_render_view() {
    // V saves the camera beside the scene (room.glb.views.json, nothing else written);
    // `render --view` renders the same pixels as the viewer showed from it.
    let _serial = serial();
    let Some(x) = Xvfb::start() else { return };
    if !have("xdotool") {
        return skip("xdotool is not installed");
    }
    let dir = common::output_dir("viewer_saved_view");
    let room = room(&dir);
    // V names the view "view 1" only in a scene without saved views.
    let _ = std::fs::remove_file(dir.join("room.glb.views.json"));
    let shown = dir.join("shown.png");
    let same = [
        "--width",
        "160",
        "--height",
        "120",
        "--spp",
        "4",
        "--exposure",
        "0",
    ];
    let mut args = vec!["view", room.to_str().unwrap(), "--no-overlay"];
    args.extend(same);
    args.extend(["--screenshot", shown.to_str().unwrap()]);
    let mut viewer = Viewer::spawn(viewer_command(&x, &dir, &args));
    viewer.wait_for("reached 4 spp");
    let wid = x.find_window();
    x.xdotool(&["windowfocus", "--sync", &wid]);
    // Turn and step aside, then save.
    x.xdotool(&["mousemove", "--window", &wid, "80", "60"]);
    x.xdotool(&["mousedown", "3"]);
    x.xdotool(&["mousemove", "--window", &wid, "110", "70"]);
    x.xdotool(&["mouseup", "3"]);
    x.xdotool(&["keydown", "a"]);
    std::thread::sleep(Duration::from_millis(300));
    x.xdotool(&["keyup", "a"]);
    viewer.wait_for("reached 4 spp");
    x.xdotool(&["key", "v"]);
    let line = viewer.wait_for("saved view");
    assert!(line.contains("room.glb.views.json"), "{line}");
    x.xdotool(&["key", "ctrl+q"]);
    viewer.wait_for("saved");
    assert!(viewer.wait_exit().success());
    let rendered = dir.join("rendered.png");
    let mut render = Command::new(binary());
    render
        .args([
            "render",
            room.to_str().unwrap(),
            "-o",
            rendered.to_str().unwrap(),
        ])
        .args(["--view", "view 1", "--device", &test_device()])
        .args(same);
    let out = run_to_exit(&mut render);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        same_pixels(&shown, &rendered),
        "render --view differs from the viewer"
    );
    // A wrong name is one line naming the file and the views it has.
    let out = run_to_exit(
        Command::new(binary())
            .args([
                "render",
                room.to_str().unwrap(),
                "-o",
                rendered.to_str().unwrap(),
            ])
            .args(["--view", "nope"]),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("view 1") && err.lines().count() == 1, "{err}");
}

/// Grain: the mean absolute difference between each pixel and its 4×4 block's mean.
fn grain(image: &Gray) -> f32 {
    let blocks = image.blocks(4);
    let bw = image.width / 4;
    let (w, h) = (bw * 4, (image.height / 4) * 4);
    let mut sum = 0.0;
    for y in 0..h {
        for x in 0..w {
            sum += (image.at(x, y) - blocks[(y / 4) * bw + x / 4]).abs();
        }
    }
    sum / (w * h) as f32
}

#[test]
fn n_shows_the_image_denoised() {
    let _serial = serial();
    let Some(x) = Xvfb::start() else { return };
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "--width",
        "320",
        "--height",
        "240",
        "--spp",
        "4",
        "--no-overlay",
        "--exposure",
        "1.2",
        "--tonemap",
        "aces",
    ];
    let mut v = Viewer::spawn(viewer_command(&x, dir.path(), &args));
    let wid = x.find_window();
    x.xdotool(&["windowfocus", "--sync", &wid]);
    v.wait_for("reached 4 spp");
    x.xdotool(&["key", "F12"]);
    let raw = load(&v.screenshot_path(dir.path()));
    // N: the guide buffers are rendered, the image starts again and is shown denoised.
    x.xdotool(&["key", "n"]);
    v.wait_for("reached 4 spp");
    std::thread::sleep(Duration::from_secs(1));
    x.xdotool(&["key", "F12"]);
    let denoised = load(&v.screenshot_path(dir.path()));
    denoised.assert_not_blank("the denoised screenshot");
    let (before, after) = (grain(&raw), grain(&denoised));
    println!("grain at 4 spp: raw {before:.4}, denoised {after:.4}");
    assert!(
        after * 2.5 < before,
        "grain raw {before:.4}, denoised {after:.4}"
    );
    // The same picture: block means agree.
    let moved = picture_difference(&raw, &denoised);
    assert!(moved < 0.05, "the denoised picture differs by {moved:.3}");
}

/// Where `rgb` lies on the heat maps' palette (blue 0, green ½, red 1), or `None` off it.
fn heat(rgb: [u8; 3]) -> Option<f32> {
    let [r, g, b] = rgb.map(f32::from);
    let on_palette = r.min(b) <= 1.0 && (r + g + b - 255.0).abs() <= 2.0;
    on_palette.then(|| match r > 0.0 {
        true => 0.5 + r / 510.0,
        false => g / 510.0,
    })
}

/// The mean heat over the block of `rgb` (width `w`) from `(x0, y0)` to `(x1, y1)` in
/// fractions of the image.
fn mean_heat(rgb: &image::RgbImage, (x0, y0): (f32, f32), (x1, y1): (f32, f32)) -> f32 {
    let (w, h) = (rgb.width() as f32, rgb.height() as f32);
    let (mut sum, mut n) = (0.0, 0.0);
    for y in (y0 * h) as u32..(y1 * h) as u32 {
        for x in (x0 * w) as u32..(x1 * w) as u32 {
            sum += heat(rgb.get_pixel(x, y).0).unwrap();
            n += 1.0;
        }
    }
    sum / n
}

#[test]
fn m_shows_the_samples_and_error_heat_maps() {
    // With adaptive sampling (here at threshold 0.05 from the command line) M shows the
    // samples each pixel took, then each pixel's error estimate against the threshold (blue a
    // quarter of it or less, green at it, red four times or more), then the image again. On
    // the bundled box at 64 spp the void around the box (black: no variance, error 0) is blue
    // in both maps, having stopped at the minimum of 48 samples, while inside the box, lit
    // walls and shadows alike (their errors measured alike), most pixels keep sampling.
    let Some((_serial, x, dir)) = interactive("viewer_heat_maps") else {
        return;
    };
    let stats = dir.join("stats.jsonl");
    let _ = std::fs::remove_file(&stats);
    let _ = std::fs::remove_dir_all(dir.join("screenshots"));
    let options = "--width 320 --height 240 --spp 64 --noise-threshold 0.05 --no-overlay";
    let args: Vec<&str> = options
        .split(' ')
        .chain(["--stats-file", stats.to_str().unwrap()])
        .collect();
    let mut v = Viewer::spawn(viewer_command(&x, &dir, &args));
    let wid = x.find_window();
    x.xdotool(&["windowfocus", "--sync", &wid]);
    v.wait_for("reached 64 spp");
    x.xdotool(&["key", "F12"]);
    let image = v.screenshot_path(&dir);
    let first = stats_lines(&stats);
    assert!(
        first.iter().all(|l| l["heat_map"].is_null()),
        "a heat map before M"
    );
    let converged = first
        .iter()
        .rev()
        .find_map(|l| l["converged_share"].as_f64())
        .expect("the converged share in the stats");
    // The void around the box is a quarter of the window.
    assert!((0.2..0.9).contains(&converged), "{converged} converged");
    x.xdotool(&["key", "m"]);
    wait_for_image(&stats, "the samples map", |l| {
        l["heat_map"] == "samples per pixel"
    });
    x.xdotool(&["key", "F12"]);
    let samples = image::open(v.screenshot_path(&dir)).unwrap().to_rgb8();
    // Two counts: 48 (blue) and 64 (red).
    assert!(
        samples
            .pixels()
            .all(|p| p.0 == [0, 0, 255] || p.0 == [255, 0, 0]),
        "the samples map has other colours than blue (48) and red (64)"
    );
    let corner = (0.0, 0.0);
    let (void, inside) = ((0.02, 0.05), ((0.4, 0.4), (0.6, 0.6)));
    assert_eq!(mean_heat(&samples, corner, void), 0.0, "the void: blue");
    assert!(
        mean_heat(&samples, inside.0, inside.1) > 0.5,
        "the box: mostly red"
    );
    x.xdotool(&["key", "m"]);
    wait_for_image(&stats, "the error map", |l| l["heat_map"] == "error");
    x.xdotool(&["key", "F12"]);
    let error = image::open(v.screenshot_path(&dir)).unwrap().to_rgb8();
    let off: Vec<_> = error.pixels().filter(|p| heat(p.0).is_none()).collect();
    assert!(
        off.is_empty(),
        "{} pixels off the palette, e.g. {:?}",
        off.len(),
        off.first()
    );
    let (void_heat, box_heat) = (
        mean_heat(&error, corner, void),
        mean_heat(&error, inside.0, inside.1),
    );
    println!("error map: void {void_heat:.2}, box {box_heat:.2}; {converged:.2} converged");
    assert_eq!(void_heat, 0.0, "the void's error is not 0");
    assert!(
        box_heat > 0.25,
        "the box's error map is cold: {box_heat:.2}"
    );
    // M again: the image.
    x.xdotool(&["key", "m"]);
    std::thread::sleep(Duration::from_secs(1));
    x.xdotool(&["key", "F12"]);
    let back = v.screenshot_path(&dir);
    assert!(
        same_pixels(&image, &back),
        "the image after the maps is another"
    );
}
