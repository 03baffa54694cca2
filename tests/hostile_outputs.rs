//! Outputs that must never destroy anything, on the real binary: an input written over (under
//! its own name or another), a symbolic link, a device node or FIFO replaced by a regular
//! file, and two writers racing for one new name.

mod common;
use common::{refused, repo_file, vmc, TempDir, BIN};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn error_of(o: &Output) -> String {
    refused(o, "the write").trim_end().to_string()
}

fn spindle_data(dir: &Path) -> PathBuf {
    let to = dir.join("d.csv");
    std::fs::copy(
        repo_file("tests/data/spindle-thermal/train_every60s.csv"),
        &to,
    )
    .unwrap();
    to
}

const FIT: [&str; 9] = [
    "fit-thermal",
    "--data",
    "d.csv",
    "--inputs",
    "t1_degc,t2_degc",
    "--outputs",
    "ch1_um",
    "--arch",
    "linear",
];

#[test]
fn an_input_is_never_written_over_even_with_force() {
    let t = TempDir::new("input");
    let data = spindle_data(t.path());
    let before = std::fs::read(&data).unwrap();
    let fit = vmc(t.path(), &[&FIT[..], &["-o", "m.json"]].concat());
    assert!(fit.status.success(), "{fit:?}");
    // The measured data as the predictions' file, by its name and through a hard link.
    std::fs::hard_link(&data, t.path().join("alias.csv")).unwrap();
    for out in ["d.csv", "alias.csv", "./sub/../d.csv"] {
        std::fs::create_dir_all(t.path().join("sub")).unwrap();
        let o = vmc(
            t.path(),
            &[
                "predict-thermal",
                "--model",
                "m.json",
                "--data",
                "d.csv",
                "-o",
                out,
                "--force",
            ],
        );
        let err = error_of(&o);
        assert!(err.contains("is an input of this command"), "{err}");
    }
    // The model file as the model's own output.
    let again = vmc(t.path(), &[&FIT[..], &["-o", "d.csv", "--force"]].concat());
    assert!(error_of(&again).contains("is an input"));
    assert_eq!(std::fs::read(&data).unwrap(), before);
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_is_refused_and_its_target_kept() {
    let t = TempDir::new("link");
    std::fs::write(t.path().join("precious.txt"), "keep").unwrap();
    std::os::unix::fs::symlink("precious.txt", t.path().join("cal.csv")).unwrap();
    let o = vmc(
        t.path(),
        &[
            "calibrate",
            "--measure-every-min",
            "120",
            "-o",
            "cal.csv",
            "--force",
        ],
    );
    assert!(error_of(&o).contains("is a symbolic link"));
    let meta = std::fs::symlink_metadata(t.path().join("cal.csv")).unwrap();
    assert!(meta.file_type().is_symlink());
    assert_eq!(
        std::fs::read_to_string(t.path().join("precious.txt")).unwrap(),
        "keep"
    );
}

#[cfg(unix)]
#[test]
fn a_device_is_written_through_with_force_and_never_replaced() {
    use std::os::unix::fs::FileTypeExt;
    let t = TempDir::new("dev");
    let args = ["calibrate", "--measure-every-min", "120", "-o", "/dev/null"];
    let refused = vmc(t.path(), &args);
    assert!(error_of(&refused).contains("--force"));
    let o = vmc(t.path(), &[&args[..], &["--force"]].concat());
    assert!(o.status.success(), "{o:?}");
    let meta = std::fs::symlink_metadata("/dev/null").unwrap();
    assert!(meta.file_type().is_char_device());
}

#[cfg(unix)]
#[test]
fn a_fifo_receives_the_contents_and_stays_a_fifo() {
    use std::io::Read;
    use std::os::unix::fs::FileTypeExt;
    let t = TempDir::new("fifo");
    let fifo = t.path().join("pipe.csv");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("no mkfifo here: skipped");
        return;
    }
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut s = String::new();
            std::fs::File::open(fifo)
                .unwrap()
                .read_to_string(&mut s)
                .unwrap();
            s
        })
    };
    let o = vmc(
        t.path(),
        &[
            "calibrate",
            "--measure-every-min",
            "120",
            "-o",
            "pipe.csv",
            "--force",
        ],
    );
    assert!(o.status.success(), "{o:?}");
    let got = reader.join().unwrap();
    assert!(got.starts_with('#') || got.contains("time_s"), "{got:.200}");
    let meta = std::fs::symlink_metadata(&fifo).unwrap();
    assert!(meta.file_type().is_fifo());
}

#[test]
fn of_writers_racing_for_one_new_name_exactly_one_wins_and_its_file_stays() {
    let t = TempDir::new("race");
    // Different seeds give different files, so the survivor can be matched to its writer.
    let children: Vec<_> = (1..=4)
        .map(|seed| {
            let seed = seed.to_string();
            Command::new(BIN)
                .args([
                    "calibrate",
                    "--measure-every-min",
                    "120",
                    "--seed",
                    &seed,
                    "-o",
                    "r.csv",
                ])
                .current_dir(t.path())
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let outcomes: Vec<Output> = children
        .into_iter()
        .map(|c| c.wait_with_output().unwrap())
        .collect();
    let winners = outcomes.iter().filter(|o| o.status.success()).count();
    let losers: Vec<String> = outcomes
        .iter()
        .filter(|o| !o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stderr).to_string())
        .collect();
    // The check before the work refuses late starters; the exclusive link refuses the rest.
    assert_eq!(winners, 1, "{losers:?}");
    for l in &losers {
        assert!(l.contains("already exists"), "{l}");
    }
    let names: Vec<_> = std::fs::read_dir(t.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 1, "no temporary file left: {names:?}");
}
