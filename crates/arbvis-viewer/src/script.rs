//! Scripted UI interaction for tests, demos and measurements under Xvfb: one action per
//! line, run frame by frame. Pointer and key actions go through egui's real input path
//! (events injected into the frame's raw input), so a script clicks the same widgets a
//! user would; `set` hands a value to the labelled widget as typing or choosing it would.
//!
//! ```text
//! wait 3                          # let 3 frames pass
//! click Screenshot                # press and release the primary button on the widget so labelled
//! click-at primary alpha 0.5 0.2  # ... at (FX, FY) of the widget: fractions of its width and
//!                                 #     height from its top-left corner
//! right-click-at LABEL FX FY      # the secondary button there (removes an alpha-curve point)
//! double-click-at LABEL FX FY     # a double click there (also removes a curve point)
//! drag-on primary alpha 0.5 0.2 30 -10  # press at (FX, FY) of the widget, move by (DX, DY)
//!                                 #     points, release (drags an alpha-curve point)
//! drag 40 0                       # drag across the 3D view from its centre (arcball)
//! scroll 120                      # scroll over the 3D view by DY points (zoom)
//! set primary Cr 0.25             # give a slider / number its value, a check box true or
//! set primary table magma         #     false, a choice one of its options (by name)
//! set layer 0 colour = layer F3   # ` = ` when the value has spaces
//! key Home                        # press and release a key (egui's key names): Home resets
//!                                 #     the camera, F12 takes a screenshot
//! resize 1280 800                 # resize the window (pixels)
//! idle 1000                       # ask for no frame for 1000 ms; prints to stdout how many
//!                                 #     frames were drawn meanwhile (0 when the viewer waits)
//! print Clip stats                # print a labelled text line to stdout as `print LABEL:
//!                                 #     TEXT` (the clip editor's build time and memory)
//! check layout                    # every control, scrolled into view in turn, lies whole
//!                                 #     inside the window and the window inside the
//!                                 #     screen; overlay labels and legends lie apart and
//!                                 #     inside the view; prints each rectangle as
//!                                 #     `layout: ...` lines
//! window-shot                     # write the whole window as arbvis-window-NNN.png
//! measure 20 full                 # draw 20 frames, printing frames per second to stdout:
//!                                 #     `full` (the volume redrawn at full quality each
//!                                 #     frame), `interactive` (at the interactive quality, as
//!                                 #     while dragging) or `ui` (the kept volume, UI only)
//! quit                            # close the window (also implied at the end)
//! ```
//!
//! Labels are the widgets' own texts (`Save tables`, `Lock secondary`, `primary Cr`,
//! `Interactive quality`, ...); the numbers of an action follow its label. Every action
//! must take effect: a label that no widget has, a widget that is disabled or cannot be
//! scrolled into view, a click the widget does not take, a value it refuses and a viewer
//! action that fails (a screenshot that cannot be written, ...) each stop the viewer with
//! an error naming the script line.

use std::path::Path;

/// One scripted action.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Let frames pass.
    Wait(u32),
    /// Click a widget: its label, where (fractions of its rectangle; centre when `None`),
    /// and how.
    Click {
        /// The widget's label.
        label: String,
        /// `(fx, fy)` from the top-left corner, each in 0..=1.
        at: Option<(f32, f32)>,
        /// Primary, secondary or double.
        kind: ClickKind,
    },
    /// Press on a widget at `(fx, fy)` of it, move by `(dx, dy)` points, release.
    DragOn {
        /// The widget's label.
        label: String,
        /// Fractions of its rectangle.
        at: (f32, f32),
        /// Points.
        by: (f32, f32),
    },
    /// Drag across the 3D view by (dx, dy) points, from its centre.
    Drag(f32, f32),
    /// Scroll over the 3D view by this many points.
    Scroll(f32),
    /// Give the labelled widget a value (number, `true`/`false`, or an option's name).
    Set {
        /// The widget's label.
        label: String,
        /// The value as written.
        value: String,
    },
    /// Press and release a key, by egui's name.
    Key(String),
    /// Resize the window to (width, height) pixels.
    Resize(u32, u32),
    /// Ask for no frames for this many milliseconds; print the frames drawn.
    Idle(u64),
    /// Draw this many frames in a mode and print the frame rate.
    Measure(u32, MeasureMode),
    /// Print what the labelled text line shows.
    Print(String),
    /// Check that every control fits the window and the overlay's items lie apart.
    CheckLayout,
    /// Write the whole window as a picture.
    WindowShot,
    /// Close the viewer.
    Quit,
}

/// Which button, how often.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClickKind {
    /// The primary button once.
    Primary,
    /// The secondary button once.
    Secondary,
    /// The primary button twice.
    Double,
}

/// What `measure` times.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeasureMode {
    /// The volume drawn at full quality every frame (the camera turning a little).
    Full,
    /// The volume drawn at the interactive quality every frame (as while dragging).
    Interactive,
    /// The kept volume image and the UI only.
    Ui,
}

impl MeasureMode {
    /// The name scripts use.
    pub fn name(self) -> &'static str {
        match self {
            MeasureMode::Full => "full",
            MeasureMode::Interactive => "interactive",
            MeasureMode::Ui => "ui",
        }
    }
}

/// One action and where it was written.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// 1-based line in the script.
    pub line: usize,
    /// The line as written (comments and outer blanks removed).
    pub text: String,
    /// The action.
    pub action: Action,
}

/// A parsed script.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Script {
    /// Where it came from (errors name it).
    pub origin: String,
    /// The steps, in order.
    pub steps: Vec<Step>,
}

/// A script that could not be read or parsed.
#[derive(Debug, thiserror::Error)]
pub enum ScriptError {
    /// The file could not be read.
    #[error("{path}: {error}")]
    File {
        /// The script file.
        path: String,
        /// What failed.
        error: std::io::Error,
    },
    /// A line that is not an action.
    #[error("{path}:{line}: {message}")]
    Line {
        /// The script file.
        path: String,
        /// 1-based line.
        line: usize,
        /// What was expected.
        message: String,
    },
}

/// Every action word, for errors.
const WORDS: &str = "wait, click, click-at, right-click-at, double-click-at, drag-on, drag, scroll, set, key, resize, idle, measure, print, check layout, window-shot, quit";

impl Script {
    /// Read a script file.
    pub fn load(path: &Path) -> Result<Script, ScriptError> {
        let text = arbvis_core::input::read_text(path, arbvis_core::input::MAX_SMALL_TEXT_BYTES)
            .map_err(|e| ScriptError::File {
                path: path.display().to_string(),
                error: e,
            })?;
        Script::parse(&text, &path.display().to_string())
    }

    /// Parse script text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Script, ScriptError> {
        let mut steps = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let action = parse_action(line).map_err(|message| ScriptError::Line {
                path: origin.to_string(),
                line: i + 1,
                message,
            })?;
            steps.push(Step {
                line: i + 1,
                text: arbvis_core::input::shorten(line, 80),
                action,
            });
        }
        Ok(Script {
            origin: origin.to_string(),
            steps,
        })
    }
}

/// Arguments an action word cannot take.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
enum ArgError {
    /// Not the words and numbers the action takes.
    #[error("{word} takes {usage}, got {got:?}")]
    Usage {
        /// The action word.
        word: String,
        /// What it takes.
        usage: String,
        /// What followed it (shortened).
        got: String,
    },
    /// A point in a widget outside it.
    #[error("{word}: FX and FY are fractions of the widget, 0..=1; got {} {}", .at[0], .at[1])]
    Fractions {
        /// The action word.
        word: String,
        /// The fractions given.
        at: [f32; 2],
    },
}

/// The message, for the line that holds the action.
impl From<ArgError> for String {
    fn from(e: ArgError) -> String {
        e.to_string()
    }
}

impl ArgError {
    fn usage(word: &str, usage: &str, rest: &str) -> ArgError {
        ArgError::Usage {
            word: word.to_string(),
            usage: usage.to_string(),
            got: arbvis_core::input::shorten(rest, 60),
        }
    }
}

/// Split `rest` into a label and its last `n` words parsed as finite numbers.
fn label_and_numbers(
    word: &str,
    rest: &str,
    n: usize,
    usage: &str,
) -> Result<(String, Vec<f32>), ArgError> {
    let words: Vec<&str> = rest.split_whitespace().collect();
    let bad = || ArgError::usage(word, usage, rest);
    if words.len() < n + 1 {
        return Err(bad());
    }
    let (label, numbers) = words.split_at(words.len() - n);
    let numbers: Vec<f32> = numbers
        .iter()
        .map(|s| s.parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    Ok((label.join(" "), numbers))
}

fn fractions(word: &str, f: &[f32]) -> Result<(f32, f32), ArgError> {
    if f.iter().any(|v| !(0.0..=1.0).contains(v)) {
        return Err(ArgError::Fractions {
            word: word.to_string(),
            at: [f[0], f[1]],
        });
    }
    Ok((f[0], f[1]))
}

fn numbers<const N: usize>(word: &str, rest: &str, usage: &str) -> Result<[f32; N], ArgError> {
    let v: Option<Vec<f32>> = rest
        .split_whitespace()
        .map(|s| s.parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect();
    v.and_then(|v| <[f32; N]>::try_from(v).ok())
        .ok_or_else(|| ArgError::usage(word, usage, rest))
}

fn parse_action(line: &str) -> Result<Action, String> {
    let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
    let rest = rest.trim();
    let click = |kind| -> Result<Action, String> {
        let (label, f) = label_and_numbers(word, rest, 2, "a widget label and FX FY")?;
        Ok(Action::Click {
            label,
            at: Some(fractions(word, &f)?),
            kind,
        })
    };
    Ok(match word {
        "wait" => Action::Wait(
            rest.parse()
                .map_err(|_| format!("wait takes a frame count, got {rest:?}"))?,
        ),
        "click" if !rest.is_empty() => Action::Click {
            label: rest.to_string(),
            at: None,
            kind: ClickKind::Primary,
        },
        "click" => return Err("click needs a widget label".into()),
        "click-at" => click(ClickKind::Primary)?,
        "right-click-at" => click(ClickKind::Secondary)?,
        "double-click-at" => click(ClickKind::Double)?,
        "drag-on" => {
            let (label, f) = label_and_numbers(word, rest, 4, "a widget label and FX FY DX DY")?;
            Action::DragOn {
                label,
                at: fractions(word, &f[..2])?,
                by: (f[2], f[3]),
            }
        }
        "drag" => {
            let [dx, dy] = numbers(word, rest, "two numbers DX DY")?;
            Action::Drag(dx, dy)
        }
        "scroll" => {
            let [dy] = numbers(word, rest, "one number DY")?;
            Action::Scroll(dy)
        }
        "set" => {
            // `set LABEL = VALUE` for values with spaces (a choice named "layer F3");
            // otherwise the value is the last word.
            let (label, value) = rest
                .split_once(" = ")
                .map(|(l, v)| (l.trim(), v.trim()))
                .or_else(|| {
                    rest.rsplit_once(char::is_whitespace)
                        .map(|(l, v)| (l.trim(), v))
                })
                .filter(|(l, v)| !l.is_empty() && !v.is_empty())
                .ok_or_else(|| format!("set takes a widget label and a value, got {rest:?}"))?;
            Action::Set {
                label: label.to_string(),
                value: value.to_string(),
            }
        }
        "key" => {
            if egui::Key::from_name(rest).is_none() {
                return Err(format!(
                    "key: no key named {rest:?} (egui's names: Home, F12, A, ...)"
                ));
            }
            Action::Key(rest.to_string())
        }
        "resize" => {
            let [w, h] = numbers(word, rest, "a width and a height in pixels")?;
            if !(64.0..=8192.0).contains(&w)
                || !(64.0..=8192.0).contains(&h)
                || w.fract() != 0.0
                || h.fract() != 0.0
            {
                return Err(format!(
                    "resize: each side must be a whole 64..=8192 pixels, got {rest:?}"
                ));
            }
            Action::Resize(w as u32, h as u32)
        }
        "idle" => {
            let ms: u64 = rest
                .parse()
                .ok()
                .filter(|&ms| ms <= 60_000)
                .ok_or_else(|| format!("idle takes milliseconds (at most 60000), got {rest:?}"))?;
            Action::Idle(ms)
        }
        "measure" => {
            let (n, mode) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
            let n: u32 = n
                .parse()
                .ok()
                .filter(|&n| (1..=10_000).contains(&n))
                .ok_or_else(|| {
                    format!("measure takes a frame count 1..=10000 and a mode, got {rest:?}")
                })?;
            let mode = match mode.trim() {
                "full" => MeasureMode::Full,
                "interactive" => MeasureMode::Interactive,
                "ui" => MeasureMode::Ui,
                other => {
                    return Err(format!(
                        "measure: mode must be full, interactive or ui, got {other:?}"
                    ))
                }
            };
            Action::Measure(n, mode)
        }
        "print" if !rest.is_empty() => Action::Print(rest.to_string()),
        "print" => return Err("print needs a text label".into()),
        "check" if rest == "layout" => Action::CheckLayout,
        "check" => return Err(format!("check takes `layout`, got {rest:?}")),
        "window-shot" if rest.is_empty() => Action::WindowShot,
        "window-shot" => return Err("window-shot takes nothing".into()),
        "quit" => Action::Quit,
        other => {
            return Err(format!(
                "unknown action {:?} ({WORDS})",
                arbvis_core::input::shorten(other, 40)
            ))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn actions(text: &str) -> Vec<Action> {
        Script::parse(text, "t")
            .unwrap()
            .steps
            .into_iter()
            .map(|s| s.action)
            .collect()
    }

    #[test]
    fn parses_every_action() {
        let s = Script::parse(
            "wait 2\nclick Save scene # comment\n\ndrag 10 -5\nquit\n",
            "t",
        )
        .unwrap();
        assert_eq!(
            s.steps.iter().map(|s| s.line).collect::<Vec<_>>(),
            [1, 2, 4, 5]
        );
        assert_eq!(s.steps[1].text, "click Save scene");
        assert_eq!(
            actions(
                "click-at primary alpha 0.25 0.75\nright-click-at primary alpha 0 1\n\
                 double-click-at x 1 0\ndrag-on secondary alpha 0.5 0.5 -30 12.5\n\
                 scroll -120\nset primary Cr 0.25\nset primary table magma\n\
                 set layer 0 colour = layer inline 128\n\
                 key Home\nresize 1280 800\nidle 1000\nmeasure 20 interactive\n\
                 print Clip stats\ncheck layout\nwindow-shot\n"
            ),
            vec![
                Action::Click {
                    label: "primary alpha".into(),
                    at: Some((0.25, 0.75)),
                    kind: ClickKind::Primary
                },
                Action::Click {
                    label: "primary alpha".into(),
                    at: Some((0.0, 1.0)),
                    kind: ClickKind::Secondary
                },
                Action::Click {
                    label: "x".into(),
                    at: Some((1.0, 0.0)),
                    kind: ClickKind::Double
                },
                Action::DragOn {
                    label: "secondary alpha".into(),
                    at: (0.5, 0.5),
                    by: (-30.0, 12.5)
                },
                Action::Scroll(-120.0),
                Action::Set {
                    label: "primary Cr".into(),
                    value: "0.25".into()
                },
                Action::Set {
                    label: "primary table".into(),
                    value: "magma".into()
                },
                Action::Set {
                    label: "layer 0 colour".into(),
                    value: "layer inline 128".into()
                },
                Action::Key("Home".into()),
                Action::Resize(1280, 800),
                Action::Idle(1000),
                Action::Measure(20, MeasureMode::Interactive),
                Action::Print("Clip stats".into()),
                Action::CheckLayout,
                Action::WindowShot,
            ]
        );
    }

    #[test]
    fn errors_name_the_line() {
        let e = Script::parse("wait 1\nwait x\n", "s.txt").unwrap_err();
        assert!(matches!(e, ScriptError::Line { line: 2, .. }), "{e}");
        assert!(e.to_string().starts_with("s.txt:2: "), "{e}");
        let missing = Script::load(Path::new("nothere.txt"))
            .unwrap_err()
            .to_string();
        assert!(
            missing.starts_with("nothere.txt: no such file (looked for /"),
            "{missing}"
        );
        for bad in [
            "jump 3",
            "drag 1",
            "drag 1 NaN",
            "click",
            "click-at 0.5 0.5",
            "click-at w 1.5 0",
            "drag-on w 0.5 0.5 3",
            "set w",
            "set 3",
            "key NoSuchKey",
            "resize 10 10",
            "resize 100.5 200",
            "idle -1",
            "idle 99999999",
            "measure 0 full",
            "measure 10 fast",
            "scroll inf",
            "print",
            "check",
            "check widgets",
            "window-shot now",
        ] {
            let e = Script::parse(&format!("wait 1\n{bad}\n"), "s").unwrap_err();
            assert!(e.to_string().starts_with("s:2: "), "{bad}: {e}");
        }
    }
}
