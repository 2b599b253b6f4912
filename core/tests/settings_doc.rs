//! README.md and docs/grbl.md carry the settings table; this test keeps both equal to
//! the code.
//! Regenerate with `UPDATE_SNAPSHOTS=1 cargo test -p inkstep-core --test settings_doc ...`.

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

fn check(file: &str) {
    let path = format!("{}/../{file}", env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(&path).expect(file);
    let start = doc.find(BEGIN).expect("begin marker") + BEGIN.len();
    let end = doc.find(END).expect("end marker");
    let want = table();
    if std::env::var_os("UPDATE_SNAPSHOTS").is_some_and(|v| v == "1") {
        let new = format!("{}{}{}", &doc[..start], want, &doc[end..]);
        std::fs::write(&path, new).expect(file);
        return;
    }
    assert_eq!(
        &doc[start..end],
        want,
        "{file} is stale: rerun with UPDATE_SNAPSHOTS=1"
    );
}

#[test]
fn settings_table_in_docs_matches_the_code() {
    check("docs/grbl.md");
}

#[test]
fn settings_table_in_readme_matches_the_code() {
    check("README.md");
}
