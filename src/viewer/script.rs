//! Scripted UI interaction for tests and demos under Xvfb: one action per line, run
//! frame by frame through egui's real input path (pointer events injected into the
//! frame's raw input), so a script clicks the same widgets a user would.
//!
//! ```text
//! wait 3                 # let 3 frames pass
//! click Screenshot       # press and release the primary button on the widget so labelled
//! drag 40 0              # drag across the GL view by (dx, dy) points (arcball)
//! quit                   # close the window (also implied at the end of the script)
//! ```

use std::path::Path;

/// One scripted action.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Let frames pass.
    Wait(u32),
    /// Click the widget whose label is this text.
    Click(String),
    /// Drag across the GL view by (dx, dy) points, from its centre.
    Drag(f32, f32),
    /// Close the viewer.
    Quit,
}

/// A parsed script.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Script {
    /// The actions, in order.
    pub actions: Vec<Action>,
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

impl Script {
    /// Read a script file.
    pub fn load(path: &Path) -> Result<Script, ScriptError> {
        let text =
            crate::input::read_text(path, crate::input::MAX_SMALL_TEXT_BYTES).map_err(|e| {
                ScriptError::File {
                    path: path.display().to_string(),
                    error: e,
                }
            })?;
        Script::parse(&text, &path.display().to_string())
    }

    /// Parse script text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Script, ScriptError> {
        let mut actions = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let bad = |message: String| ScriptError::Line {
                path: origin.to_string(),
                line: i + 1,
                message,
            };
            let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
            let rest = rest.trim();
            let action = match word {
                "wait" => Action::Wait(
                    rest.parse()
                        .map_err(|_| bad(format!("wait takes a frame count, got {rest:?}")))?,
                ),
                "click" if !rest.is_empty() => Action::Click(rest.to_string()),
                "click" => return Err(bad("click needs a widget label".into())),
                "drag" => {
                    let v: Vec<f32> = rest
                        .split_whitespace()
                        .map(|s| s.parse::<f32>())
                        .collect::<Result<_, _>>()
                        .map_err(|_| bad(format!("drag takes two numbers, got {rest:?}")))?;
                    match v[..] {
                        [dx, dy] if dx.is_finite() && dy.is_finite() => Action::Drag(dx, dy),
                        _ => return Err(bad(format!("drag takes two numbers, got {rest:?}"))),
                    }
                }
                "quit" => Action::Quit,
                other => {
                    return Err(bad(format!(
                        "unknown action {other:?} (wait, click, drag, quit)"
                    )))
                }
            };
            actions.push(action);
        }
        Ok(Script { actions })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_action() {
        let s = Script::parse(
            "wait 2\nclick Save scene # comment\n\ndrag 10 -5\nquit\n",
            "t",
        )
        .unwrap();
        assert_eq!(
            s.actions,
            vec![
                Action::Wait(2),
                Action::Click("Save scene".into()),
                Action::Drag(10.0, -5.0),
                Action::Quit
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
        assert!(Script::parse("jump 3", "s").is_err());
        assert!(Script::parse("drag 1", "s").is_err());
        assert!(Script::parse("drag 1 NaN", "s").is_err());
    }
}
