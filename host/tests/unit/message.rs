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
