use et_host::message::one_line;

#[derive(Debug, thiserror::Error)]
enum Outer {
    #[error("mesh: {0}")]
    Mesh(#[from] std::io::Error),
}

#[test]
fn a_cause_already_in_the_message_is_said_once() {
    let inner = std::io::Error::other("too few triangles");
    let e = anyhow::Error::from(Outer::from(inner)).context("sheet.toml");
    assert_eq!(one_line(&e), "sheet.toml: mesh: too few triangles");
    let plain = anyhow::anyhow!("no port").context("et stream");
    assert_eq!(one_line(&plain), "et stream: no port");
}

#[derive(Debug, thiserror::Error)]
enum Parse {
    #[error("scene.toml: {}", source.to_string().trim_end())]
    Toml { source: std::io::Error },
}

#[test]
fn a_cause_said_with_its_line_break_trimmed_is_said_once() {
    // As a scene's TOML error: its message (a snippet of the file) ends in a line break the
    // outer message trims.
    let source = std::io::Error::other("TOML parse error at line 6\n  |\ninvalid type\n");
    let e = anyhow::Error::from(Parse::Toml { source });
    assert_eq!(
        one_line(&e),
        "scene.toml: TOML parse error at line 6\n  |\ninvalid type"
    );
}
