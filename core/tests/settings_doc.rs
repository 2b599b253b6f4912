//! docs/grbl.md carries the settings table; this test keeps it equal to the code.
//! Regenerate with `INKSTEP_BLESS=1 cargo test -p inkstep-core --test settings_doc ...`.

use inkstep_core::settings::{Kind, TABLE};

const BEGIN: &str = "<!-- settings:begin (generated from core/src/settings.rs) -->\n";
const END: &str = "<!-- settings:end -->";

fn table() -> String {
    let mut s = String::from("| $ | Meaning | Default | Range |\n|---|---|---|---|\n");
    for d in TABLE.iter() {
        let fmt = |v: f32| match d.kind {
            Kind::Float => format!("{v:.3}"),
            _ => format!("{}", v as i64),
        };
        s.push_str(&format!(
            "| ${} | {} | {} | {} .. {} |\n",
            d.number,
            d.name,
            fmt(d.default),
            fmt(d.min),
            fmt(d.max)
        ));
    }
    s
}

#[test]
fn settings_table_in_docs_matches_the_code() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/grbl.md");
    let doc = std::fs::read_to_string(path).expect("docs/grbl.md");
    let start = doc.find(BEGIN).expect("begin marker") + BEGIN.len();
    let end = doc.find(END).expect("end marker");
    let want = table();
    if std::env::var_os("INKSTEP_BLESS").is_some() {
        let new = format!("{}{}{}", &doc[..start], want, &doc[end..]);
        std::fs::write(path, new).expect("write docs/grbl.md");
        return;
    }
    assert_eq!(
        &doc[start..end],
        want,
        "docs/grbl.md is stale: rerun with INKSTEP_BLESS=1"
    );
}
