//! The README's pictures are made by the README's commands: every command of its "Gallery
//! commands" block runs (from the repository root, as a user would) into a temporary file,
//! which must match the committed picture it names (the tolerance of
//! [`common::png_close`]). A command whose shared dataset is absent is skipped with a
//! message. `VOLUX_UPDATE_GALLERY=1` rewrites the pictures after a deliberate change. A
//! command that measures (`--measure`) must print the length the README states.
use std::path::{Path, PathBuf};

mod common;

/// The repository root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The commands of the README's gallery block, continuation lines joined, split into words.
fn gallery_commands() -> Vec<Vec<String>> {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let begin = readme
        .find("<!-- gallery: begin -->")
        .expect("gallery block");
    let end = readme
        .find("<!-- gallery: end -->")
        .expect("gallery block end");
    let block = readme[begin..end].replace("\\\n", " ");
    block
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("volux "))
        .map(|l| l.split_whitespace().skip(1).map(str::to_string).collect())
        .collect()
}

/// A measured picture's length, printed by its command, is the one the README states (to
/// 0.1 mm).
fn the_readme_states_the_length(picture: &str, stdout: &str) {
    let length: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("length: "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{picture}: no length printed in {stdout:?}"));
    let stated = format!("{length:.1} mm");
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    assert!(
        readme.contains(&stated),
        "{picture}: the command measures {stated}, which the README does not state"
    );
    eprintln!("{picture}: measured {stated}");
}

#[test]
fn every_gallery_picture_is_made_by_its_command() {
    let commands = gallery_commands();
    assert!(commands.len() >= 6, "the gallery lists its commands");
    let update = std::env::var_os("VOLUX_UPDATE_GALLERY").is_some();
    let dir = tempfile::tempdir().unwrap();
    let mut pictures = Vec::new();
    for mut args in commands {
        let missing = args
            .iter()
            .find(|a| a.starts_with("../shared/") && !root().join(a).exists());
        if let Some(m) = missing {
            volux_testkit::data::skip_or_fail(&format!(
                "the gallery command for {m} has no dataset"
            ));
            continue;
        }
        let o = args
            .iter()
            .position(|a| a == "-o")
            .expect("each command names its picture");
        let picture = args[o + 1].clone();
        assert!(picture.starts_with("docs/images/"), "{picture}");
        assert!(!pictures.contains(&picture), "{picture} is made twice");
        pictures.push(picture.clone());
        let out = dir.path().join(Path::new(&picture).file_name().unwrap());
        args[o + 1] = out.to_string_lossy().into_owned();
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let run = common::volux(&refs, &root());
        assert!(
            run.status.success(),
            "{picture}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        if args.iter().any(|a| a == "--measure") {
            the_readme_states_the_length(&picture, &String::from_utf8_lossy(&run.stdout));
        }
        let committed = root().join(&picture);
        if update {
            std::fs::copy(&out, &committed).unwrap();
            eprintln!("updated {picture}");
            continue;
        }
        match common::png_close(&out, &committed) {
            Ok(figures) => eprintln!("{picture}: {figures}"),
            Err(why) => panic!("{picture} is not what its README command makes: {why}"),
        }
    }
    // Every picture the README shows is one the gallery makes.
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    for shown in readme.split("(docs/images/").skip(1) {
        let name = format!("docs/images/{}", shown.split(')').next().unwrap());
        assert!(
            gallery_commands().iter().any(|c| c.contains(&name)),
            "{name} is shown but no gallery command makes it"
        );
    }
}
