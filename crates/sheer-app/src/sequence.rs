//! A sequence of frames on the scene's one clock, shared by `sheer simulate` and `sheer render`: frame
//! `k` of a sequence that starts at `T` is the scene after `round(T·fps) + k` frames of `1/fps` each
//! ([`FlagScene::advance_frame`]), so both commands give the same particles bit for bit. Ctrl-C stops
//! a sequence between two frames; a failure or an interruption says which frames are complete.

use std::path::Path;

use crate::CliError;
use crate::frame::{FlagScene, StageTimes};
use crate::output::{FrameNames, interrupt};

/// Simulates the scene from where it is up to the frame nearest `time` (s) at its frame rate. Ctrl-C
/// (once [`interrupt::install`]ed) stops it with an error.
pub fn advance_to(flag: &mut FlagScene, time: f64) -> Result<(), CliError> {
    let fps = f64::from(flag.scene.render.fps);
    let target = (time * fps).round();
    if !(0.0..=f64::from(u32::MAX)).contains(&target) {
        return Err(CliError::new(format!(
            "cannot simulate {time} s at {fps} frames/s: {target} frames"
        )));
    }
    let mut times = StageTimes::default();
    for _ in flag.frame()..target as u64 {
        if interrupt::requested() {
            return Err(CliError::new(format!(
                "interrupted at {:.3} s of the {time} s to simulate before the first frame: nothing \
                 was written",
                flag.time()
            )));
        }
        flag.advance_frame(&mut times)?;
    }
    Ok(())
}

/// Where a sequence goes and how long it is.
pub struct Sequence<'a> {
    /// The output folder, already prepared ([`crate::output::prepare_sequence_folder`]).
    pub dir: &'a Path,
    pub names: &'a FrameNames,
    /// The extension the summary names the frames by.
    pub extension: &'static str,
    pub frames: u32,
    /// Scene time of frame 0, s.
    pub start: f64,
    /// The progress bar's word: "simulating", "rendering".
    pub verb: &'static str,
}

impl Sequence<'_> {
    /// Which frames are complete after `count` of them were written.
    fn complete(&self, count: u32) -> String {
        match count {
            0 => format!("no frame was written to {}", self.dir.display()),
            1 => format!(
                "{} in {} is complete",
                self.names.name(0, self.extension),
                self.dir.display()
            ),
            _ => format!(
                "{} … {} ({count} of {} frames) in {} are complete",
                self.names.name(0, self.extension),
                self.names.name(count - 1, self.extension),
                self.frames,
                self.dir.display()
            ),
        }
    }
}

/// Runs `sequence`: advances `flag` to its start, then for each frame advances one frame (but the
/// first) and calls `write_frame(flag, frame index, times)`. Ctrl-C ends it after the frame being
/// written, with an error that says which frames are complete; so does any failure.
pub fn run_sequence(
    flag: &mut FlagScene,
    sequence: &Sequence<'_>,
    times: &mut StageTimes,
    mut write_frame: impl FnMut(&FlagScene, u32, &mut StageTimes) -> Result<(), CliError>,
) -> Result<(), CliError> {
    advance_to(flag, sequence.start)?;
    let progress = crate::progress_bar(u64::from(sequence.frames), sequence.verb);
    for frame in 0..sequence.frames {
        let result = if frame == 0 {
            Ok(())
        } else {
            flag.advance_frame(times)
        }
        .and_then(|()| write_frame(flag, frame, times));
        if let Err(error) = result {
            progress.finish_and_clear();
            return Err(CliError::new(format!(
                "frame {frame}: {error}; {}",
                sequence.complete(frame)
            )));
        }
        progress.inc(1);
        if interrupt::requested() && frame + 1 < sequence.frames {
            progress.finish_and_clear();
            return Err(CliError::new(format!(
                "interrupted: {}",
                sequence.complete(frame + 1)
            )));
        }
    }
    progress.finish_and_clear();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use crate::simulate::{SimulateArgs, run};

    /// The positions of an OBJ frame as `sheer simulate` wrote them.
    fn obj_positions(path: &Path) -> Vec<[f64; 3]> {
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            })
            .collect()
    }

    /// `sheer simulate` and `sheer render` of one scene give the same particles bit for bit: the OBJ
    /// frames that `simulate` writes are the flag that `render`'s sequence draws at each frame. Before
    /// the scene had one clock, `render` stepped by 1/60 rounded to single precision, and its flag
    /// left `simulate`'s; the end of this test shows that such a step does give other bits.
    #[test]
    fn simulate_and_render_sequences_step_the_same_flag() {
        let dir = std::env::temp_dir().join(format!("sheer-one-clock-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let frames = 8;
        run(&SimulateArgs {
            scene: None,
            frames,
            time: 0.25,
            out_dir: dir.clone(),
            overwrite: false,
        })
        .unwrap();
        // The sequence exactly as `render` runs it, the drawing left out.
        let names = FrameNames::new(frames, &["png"]);
        let sequence = Sequence {
            dir: &dir,
            names: &names,
            extension: "png",
            frames,
            start: 0.25,
            verb: "rendering",
        };
        let mut flag = FlagScene::new(Scene::builtin_default().unwrap()).unwrap();
        let mut drawn = Vec::new();
        run_sequence(
            &mut flag,
            &sequence,
            &mut StageTimes::default(),
            |flag, _, _| {
                let sim = flag.simulation().unwrap();
                drawn.push(
                    sim.positions()
                        .iter()
                        .map(|p| p.to_array())
                        .collect::<Vec<_>>(),
                );
                Ok(())
            },
        )
        .unwrap();
        for (frame, positions) in drawn.iter().enumerate() {
            let written = obj_positions(&dir.join(format!("frame_{frame:04}.obj")));
            assert_eq!(&written, positions, "frame {frame}");
        }
        // A step of 1/60 rounded to f32 is another flag after a few frames.
        let mut rounded =
            crate::simulate::flag_simulation(&Scene::builtin_default().unwrap()).unwrap();
        for _ in 0..(15 + frames - 1) {
            rounded.step(f64::from(1.0f32 / 60.0)).unwrap();
        }
        let last: Vec<[f64; 3]> = rounded.positions().iter().map(|p| p.to_array()).collect();
        assert_ne!(&last, drawn.last().unwrap());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
