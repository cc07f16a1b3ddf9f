use et_core::ProtocolKind;
use et_core::protocol::Protocol;
use et_host::tables::*;

#[test]
fn tables_agree_with_the_core() {
    let p = Protocol::new(ProtocolKind::Opposite, 16).unwrap();
    let t = ProtocolTables::new(&p);
    assert_eq!((t.frame_len, t.p_halved, t.p_full), (192, 96, 192));
    assert_eq!(t.injections.len(), 16);
    let total: usize = t.injections.iter().map(|r| r.measurements.len()).sum();
    assert_eq!(total, t.frame_len);
    assert!(t.to_text().contains("K = 192"));
    let wide = ProtocolTables::new(&Protocol::new(ProtocolKind::Adjacent, 32).unwrap());
    assert!(wide.injections[20].mux_word.is_none());
    assert!(wide.injections[3].mux_word.is_some());
}
