//! `coordinator export`: the CSV tables hold what the MCAP log holds, to the bit, and a log
//! cut short is exported up to its break with a warning.
mod common;
use common::*;
use coordinator::mcap_log::read_topic;
use std::path::Path;

fn rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn bead_and_diagnostic_tables_equal_the_log() {
    let set = [
        "time.steps=1000".to_string(),
        "output.interval=100".to_string(),
    ];
    let out = run_scene(
        "export",
        &config("cantilever.toml"),
        &set,
        &["--in-process"],
    )
    .unwrap();
    let o = coordinator(&["export", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let log = out.join("run.mcap");
    let states = read_topic(&log, "/fibre/bead_states").unwrap();
    let beads = rows(&out.join("beads.csv"));
    let columns: Vec<String> = states[0]["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap().to_string())
        .collect();
    assert_eq!(beads[0][..4], ["step", "time", "fibre", "bead"]);
    assert_eq!(beads[0][4..], columns[..]);
    let per_message = states[0]["states"].as_array().unwrap().len();
    assert_eq!(per_message, 10);
    assert_eq!(beads.len() - 1, states.len() * per_message);
    for (m, chunk) in states.iter().zip(beads[1..].chunks(per_message)) {
        for (b, row) in chunk.iter().enumerate() {
            assert_eq!(row[0], m["step"].to_string());
            assert_eq!(row[3], b.to_string());
            for (j, cell) in row[4..].iter().enumerate() {
                let logged = m["states"][b][j].as_f64().unwrap();
                assert_eq!(cell.parse::<f64>().unwrap().to_bits(), logged.to_bits());
            }
        }
    }

    let diagnostics = read_topic(&log, "/diagnostics").unwrap();
    let table = rows(&out.join("diagnostics.csv"));
    assert_eq!(table.len() - 1, diagnostics.len());
    let col = |name: &str| table[0].iter().position(|h| h == name).unwrap();
    let k = col("kinetic_energy");
    for (m, row) in diagnostics.iter().zip(&table[1..]) {
        assert_eq!(row[col("step")], m["step"].to_string());
        let logged = m["kinetic_energy"].as_f64().unwrap();
        assert_eq!(row[k].parse::<f64>().unwrap().to_bits(), logged.to_bits());
    }

    // The scene as run (the overrides applied) runs again to the same bits.
    let scene = out.join("scene.toml");
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(
        text.contains("steps = 1000") && text.contains("interval = 100"),
        "{text}"
    );
    let again = run_scene("export-again", &scene, &[], &["--in-process"]).unwrap();
    assert_eq!(
        read_topic(&again.join("run.mcap"), "/fibre/bead_states").unwrap(),
        states
    );
    let _ = std::fs::remove_dir_all(&again);

    // A new run into the folder removes the tables of the old log, but not the scene file
    // it runs.
    let o = run_command(&scene, &out)
        .arg("--in-process")
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(scene.exists());
    for f in ["beads.csv", "diagnostics.csv"] {
        assert!(!out.join(f).exists(), "{f} left from the earlier run");
    }
    let o = run_command(&config("cantilever.toml"), &out)
        .args([
            "--in-process",
            "--set",
            "time.steps=1000",
            "--set",
            "output.interval=100",
        ])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(!scene.exists(), "the earlier run's scene.toml was left");
    let o = coordinator(&["export", out.to_str().unwrap()]);
    assert!(o.status.success());

    // One topic as JSON lines: the messages themselves.
    let o = coordinator(&["export", out.to_str().unwrap(), "--topic", "/diagnostics"]);
    assert!(o.status.success());
    let lines: Vec<serde_json::Value> = String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines, diagnostics);
    // A misspelt topic is answered with the log's topics.
    let o = coordinator(&["export", out.to_str().unwrap(), "--topic", "/diagnostic"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no messages on /diagnostic (its topics: ")
            && err.contains("/diagnostics")
            && err.contains("/fibre/bead_states"),
        "{err}"
    );

    // A log cut short (a killed run never writes the footer): what came before the break.
    let cut = out.join("cut");
    std::fs::create_dir_all(&cut).unwrap();
    let bytes = std::fs::read(&log).unwrap();
    std::fs::write(cut.join("run.mcap"), &bytes[..bytes.len() / 2]).unwrap();
    let o = coordinator(&["export", cut.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("breaks off"), "{err}");
    let partial = rows(&cut.join("beads.csv"));
    assert!(
        partial.len() > 1 && partial.len() < beads.len(),
        "{}",
        partial.len()
    );
    assert_eq!(partial[..], beads[..partial.len()]);

    // A file that is not MCAP says so.
    let fake = out.join("fake");
    std::fs::create_dir_all(&fake).unwrap();
    std::fs::write(fake.join("run.mcap"), b"step,time\n1,2\n").unwrap();
    let o = coordinator(&["export", fake.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("is not an MCAP file"), "{err}");

    // Not a run: a clear error, no panic.
    let o = coordinator(&["export", cut.join("nothing").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no run folder or MCAP file"));
    let _ = std::fs::remove_dir_all(&out);
}
