//! SVG to strokes. usvg does the SVG work (shapes to paths, styles, units,
//! `<use>`, nested `<svg>`); this module walks its tree and owns the rest:
//!
//! - Placement: each group's own transform is multiplied in on the way down.
//!   usvg 0.45's `abs_transform()` applies a `<use>` element's transform twice
//!   (three times for a nested `<svg>`), so it is never used here.
//! - Curves are flattened by adaptive subdivision until every piece lies within
//!   the tolerance of its chord *and* its length is within 0.4 % of the curve's
//!   (so tiny circles do not turn into octagons).
//! - What a pen cannot draw is reported, by name: text (unless drawn with a
//!   Hershey font: usvg, built without fonts, drops `<text>`, so each one is
//!   swapped for a small probe group before parsing, and the probe's placement
//!   tells where the text goes), images, and fills that are not hatched.
//! - Passes: Inkscape layers (`<g inkscape:groupmode="layer">`, found in the
//!   XML by id, since usvg keeps group ids but not Inkscape's attributes) or
//!   stroke colours, each a separate list of strokes.
//! - Bad input: `.svgz` is decompressed, absurd coordinates are refused with
//!   the element's name, zero-length pieces are not drawn as dots unless their
//!   line cap would show a dot.
//!
//! Output is in millimetres, y up (SVG y down is flipped about the page
//! height), so it feeds the planner and the G-code writer directly.

use crate::biarc::{fit_cubics, ArcHints, Seg};
use crate::geom::{Pt, Stroke};
use crate::hatch::{hatch, FillRule};
use anyhow::{anyhow, bail, Context, Result};
use usvg::roxmltree;
use usvg::tiny_skia_path::{PathSegment, Point, Transform};

/// CSS pixels (usvg's unit) to millimetres.
pub const MM_PER_PX: f64 = 25.4 / 96.0;

/// Largest coordinate accepted (mm): 100 m. Anything beyond is a broken file,
/// and refusing it keeps every G-code word short.
pub const MAX_MM: f64 = 100_000.0;

/// Relative length error allowed for a flattened curve piece (on top of the
/// distance tolerance).
const LEN_TOL: f64 = 4e-3;

/// Deepest element nesting accepted (Inkscape files nest a dozen or so).
const MAX_DEPTH: usize = 256;

/// The pass of what lies outside every Inkscape layer.
pub const NO_LAYER: &str = "no layer";

const PROBE: &str = "inkstep-text-probe-";

/// How strokes are split into passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LayerMode {
    /// Inkscape layers (top-level `inkscape:groupmode="layer"` groups).
    #[default]
    Layers,
    /// One pass per stroke colour.
    ByColor,
    /// Everything in one pass.
    None,
}

#[derive(Clone, Debug, PartialEq)]
pub struct SvgOptions {
    /// Largest distance of a curve from its polyline (mm).
    pub tol_mm: f64,
    pub layers: LayerMode,
    /// Hatch filled shapes: (spacing mm, angle degrees).
    pub hatch: Option<(f64, f64)>,
    /// Draw `<text>` with this Hershey font instead of leaving it out.
    pub text_font: Option<String>,
    /// Curves as arcs within this tolerance (mm), recorded in
    /// [`Drawing::arc_hints`]; None: curves flattened into lines.
    pub arcs: Option<f64>,
}

impl Default for SvgOptions {
    fn default() -> Self {
        SvgOptions {
            tol_mm: 0.05,
            layers: LayerMode::Layers,
            hatch: None,
            text_font: None,
            arcs: None,
        }
    }
}

/// One pass of the pen: a layer or a colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    pub name: String,
    pub strokes: Vec<Stroke>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkipKind {
    Text,
    Image,
    /// A fill not hatched (its outline is drawn).
    Fill,
}

impl SkipKind {
    pub fn label(self) -> &'static str {
        match self {
            SkipKind::Text => "text",
            SkipKind::Image => "image",
            SkipKind::Fill => "fill not hatched",
        }
    }
}

/// Something in the file the pen does not draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    pub kind: SkipKind,
    pub name: String,
    /// Where it is on the page (mm, y up): its outline as closed rings
    /// (inside by even-odd), for the preview.
    pub outline: Vec<Stroke>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Drawing {
    pub layers: Vec<Layer>,
    pub skipped: Vec<Skipped>,
    /// Page size (mm).
    pub page: (f64, f64),
    /// The arcs between consecutive stroke points, with [`SvgOptions::arcs`].
    pub arc_hints: ArcHints,
}

impl Drawing {
    /// All strokes, layer after layer.
    pub fn strokes(&self) -> Vec<Stroke> {
        self.layers
            .iter()
            .flat_map(|l| l.strokes.iter().cloned())
            .collect()
    }
}

/// Strokes of every visible path in the SVG text, curves flattened so that
/// no point of a curve is farther than `tol_mm` from the polyline.
pub fn strokes_from_svg(text: &str, tol_mm: f64) -> Result<Vec<Stroke>> {
    let d = read_svg(
        text.as_bytes(),
        &SvgOptions {
            tol_mm,
            layers: LayerMode::None,
            ..SvgOptions::default()
        },
    )?;
    Ok(d.strokes())
}

/// A `<text>` element as found in the XML.
struct TextInfo {
    name: String,
    /// Lines: their text (tspans with their own position are lines) and
    /// anchor (0 start, 0.5 middle, 1 end).
    lines: Vec<(String, f64)>,
    font_px: f64,
}

/// Reads an SVG (or gzip-compressed SVGZ) file.
pub fn read_svg(data: &[u8], opt: &SvgOptions) -> Result<Drawing> {
    if !(opt.tol_mm > 0.0 && opt.tol_mm.is_finite()) {
        bail!("tolerance must be a positive number of mm");
    }
    let unzipped;
    let data = if data.starts_with(&[0x1f, 0x8b]) {
        unzipped = usvg::decompress_svgz(data).map_err(|e| anyhow!("reading SVGZ: {e}"))?;
        &unzipped[..]
    } else {
        data
    };
    let text = std::str::from_utf8(data).context("the file is neither SVG text nor SVGZ")?;
    // The XML parser and usvg recurse per element level: refuse a nesting that
    // would exhaust the stack (a crash, not an error) before parsing.
    if let Some(d) = nesting_beyond(text, MAX_DEPTH) {
        bail!("parsing SVG: elements nested deeper than {MAX_DEPTH} (at least {d})");
    }
    let xml_opt = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(text, xml_opt).context("parsing SVG")?;
    // Numbers beyond f32 (usvg's precision) become infinite there, and an
    // arc to infinity makes svgtypes build segments without end: refuse them.
    for n in doc.descendants().filter(|n| n.is_element()) {
        for a in n
            .attributes()
            .filter(|a| GEOMETRY_ATTRS.contains(&a.name()))
        {
            if let Some(v) = huge_number(a.value()) {
                bail!(
                    "{} {}=\"{}\": the number {v:e} is beyond any drawing (the file is broken)",
                    n.attribute("id")
                        .map_or_else(|| format!("<{}>", n.tag_name().name()), |id| id.to_string()),
                    a.name(),
                    clip(a.value(), 30)
                );
            }
        }
    }
    let layer_ids = find_layers(&doc);
    let (probed, texts) = probe_texts(text, &doc);
    let tree = usvg::Tree::from_str(&probed, &usvg::Options::default()).context("parsing SVG")?;
    let h = tree.size().height() as f64;
    let mut w = Walker {
        opt,
        tol_px: opt.tol_mm / MM_PER_PX,
        h,
        layer_ids,
        texts,
        layers: Vec::new(),
        skipped: Vec::new(),
        cur_layer: None,
        hatch_segments: 0,
        arc_hints: ArcHints::default(),
    };
    w.walk(tree.root(), tree.root().transform())?;
    let mut layers = w.layers;
    layers.retain(|l| !l.strokes.is_empty());
    Ok(Drawing {
        layers,
        skipped: w.skipped,
        page: (tree.size().width() as f64 * MM_PER_PX, h * MM_PER_PX),
        arc_hints: w.arc_hints,
    })
}

/// Attributes that hold coordinates (colours like "#2e5566" must not count).
const GEOMETRY_ATTRS: &[&str] = &[
    "d",
    "points",
    "transform",
    "x",
    "y",
    "x1",
    "y1",
    "x2",
    "y2",
    "cx",
    "cy",
    "r",
    "rx",
    "ry",
    "width",
    "height",
    "viewBox",
    "gradientTransform",
    "patternTransform",
];

/// The first number in `s` of magnitude 1e30 or more (or one too large to
/// parse as finite), if any.
fn huge_number(s: &str) -> Option<f64> {
    let is_num = |c: char| c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '+' | '-');
    s.split(|c: char| !is_num(c))
        .filter(|t| t.bytes().any(|b| b.is_ascii_digit()))
        .find_map(|t| {
            // "1e5-2e3" is two numbers; a sign after a digit starts the next.
            let mut start = 0;
            let b = t.as_bytes();
            let mut out = None;
            for k in 1..=b.len() {
                let end = k == b.len()
                    || ((b[k] == b'-' || b[k] == b'+') && !matches!(b[k - 1], b'e' | b'E'));
                if end {
                    if let Ok(v) = t[start..k].parse::<f64>() {
                        if v.is_nan() || v.abs() >= 1e30 {
                            out = Some(v);
                            break;
                        }
                    }
                    start = k;
                }
            }
            out
        })
}

/// The element nesting depth once it exceeds `max`, scanning the markup
/// without recursion: comments, CDATA, processing instructions and the
/// doctype are skipped, quoted attribute values may hold '>'.
fn nesting_beyond(text: &str, max: usize) -> Option<usize> {
    let b = text.as_bytes();
    let skip_to = |from: usize, end: &[u8]| -> usize {
        b.get(from..)
            .and_then(|rest| rest.windows(end.len()).position(|w| w == end))
            .map_or(b.len(), |k| from + k + end.len())
    };
    let (mut i, mut depth) = (0usize, 0usize);
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &b[i..];
        if rest.starts_with(b"<!--") {
            i = skip_to(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_to(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_to(i + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            // A doctype, perhaps with an internal subset in [...].
            let close = skip_to(i + 2, b">");
            let open = rest.iter().position(|&c| c == b'[').map(|k| i + k);
            i = match open {
                Some(o) if o < close => skip_to(o, b"]>").max(close),
                _ => close,
            };
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = skip_to(i + 2, b">");
        } else {
            // A start tag: find its end outside quotes.
            let mut k = i + 1;
            let mut quote = None;
            while k < b.len() {
                match (quote, b[k]) {
                    (None, b'"') | (None, b'\'') => quote = Some(b[k]),
                    (Some(q), c) if c == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                k += 1;
            }
            if k > 0 && b.get(k - 1) != Some(&b'/') {
                depth += 1;
                if depth > max {
                    return Some(depth);
                }
            }
            i = k + 1;
        }
    }
    None
}

const INKSCAPE_NS: &str = "http://www.inkscape.org/namespaces/inkscape";

/// Top-level Inkscape layers: (group id, label).
fn find_layers(doc: &roxmltree::Document) -> Vec<(String, String)> {
    doc.descendants()
        .filter(|n| {
            n.has_tag_name("g")
                && n.attribute((INKSCAPE_NS, "groupmode")) == Some("layer")
                && !n
                    .ancestors()
                    .skip(1)
                    .any(|a| a.attribute((INKSCAPE_NS, "groupmode")) == Some("layer"))
        })
        .filter_map(|n| {
            let id = n.attribute("id")?;
            let label = n.attribute((INKSCAPE_NS, "label")).unwrap_or(id);
            Some((id.to_string(), label.to_string()))
        })
        .collect()
}

/// Font size in px from the element or its ancestors (attribute or style).
fn font_px(n: roxmltree::Node) -> f64 {
    for a in n.ancestors() {
        let from_style = a.attribute("style").and_then(|s| {
            s.split(';').find_map(|kv| {
                let (k, v) = kv.split_once(':')?;
                (k.trim() == "font-size").then(|| v.trim().to_string())
            })
        });
        if let Some(v) = from_style.or_else(|| a.attribute("font-size").map(str::to_string)) {
            if let Some(px) = length_px(&v) {
                return px;
            }
        }
    }
    16.0
}

/// A presentation property from the element or its ancestors (style first).
fn style_prop(n: roxmltree::Node, name: &str) -> Option<String> {
    n.ancestors().find_map(|a| {
        a.attribute("style")
            .and_then(|s| {
                s.split(';').find_map(|kv| {
                    let (k, v) = kv.split_once(':')?;
                    (k.trim() == name).then(|| v.trim().to_string())
                })
            })
            .or_else(|| a.attribute(name).map(str::to_string))
    })
}

/// Where a text line sits on its x: 0 from its start, 0.5 centred, 1 ending there.
fn anchor(n: roxmltree::Node) -> f64 {
    match style_prop(n, "text-anchor").as_deref() {
        Some("middle") => 0.5,
        Some("end") => 1.0,
        _ => 0.0,
    }
}

fn length_px(v: &str) -> Option<f64> {
    let v = v.trim();
    let end = v
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+' || c == 'e'))
        .unwrap_or(v.len());
    let x: f64 = v[..end].parse().ok()?;
    let k = match v[end..].trim() {
        "" | "px" => 1.0,
        "pt" => 96.0 / 72.0,
        "mm" => 96.0 / 25.4,
        "cm" => 96.0 / 2.54,
        "in" => 96.0,
        "pc" => 16.0,
        _ => return None,
    };
    (x.is_finite() && x > 0.0).then_some(x * k)
}

fn first_coord(n: roxmltree::Node, a: &str) -> Option<f64> {
    let v = n.attribute(a)?;
    let first = v
        .split(|c: char| c == ',' || c.is_whitespace())
        .find(|s| !s.is_empty())?;
    length_px(first).or_else(|| first.parse().ok())
}

/// Replaces every `<text>` with a group of the same transform holding one
/// tiny path per line: `M x y h 1 M x y v 1`, whose placement after usvg is
/// the text line's frame. The group's id names the probe.
fn probe_texts(src: &str, doc: &roxmltree::Document) -> (String, Vec<TextInfo>) {
    let mut out = String::with_capacity(src.len());
    let mut texts = Vec::new();
    let mut at = 0;
    for n in doc.descendants().filter(|n| n.has_tag_name("text")) {
        let r = n.range();
        if r.start < at {
            continue; // inside a text already replaced
        }
        let (x0, y0) = (
            first_coord(n, "x").unwrap_or(0.0),
            first_coord(n, "y").unwrap_or(0.0),
        );
        let mut lines: Vec<(f64, f64, String, f64)> = Vec::new();
        let positioned: Vec<_> = n
            .children()
            .filter(|c| c.has_tag_name("tspan") && c.attribute("y").is_some())
            .collect();
        if positioned.is_empty() {
            let t: String = n
                .descendants()
                .filter(|d| d.is_text())
                .filter_map(|d| d.text())
                .collect();
            lines.push((x0, y0, t, anchor(n)));
        } else {
            for c in positioned {
                let t: String = c
                    .descendants()
                    .filter(|d| d.is_text())
                    .filter_map(|d| d.text())
                    .collect();
                let x = first_coord(c, "x").unwrap_or(x0);
                let y = first_coord(c, "y").unwrap_or(y0);
                lines.push((x, y, t, anchor(c)));
            }
        }
        let content: Vec<(String, f64)> = lines
            .iter()
            .map(|l| (l.2.trim().to_string(), l.3))
            .collect();
        let all = content
            .iter()
            .map(|c| c.0.as_str())
            .collect::<Vec<_>>()
            .join(" ");
        let name = match n.attribute("id") {
            Some(id) => format!("{id} \"{}\"", clip(&all, 40)),
            None => format!("\"{}\"", clip(&all, 40)),
        };
        let mut g = format!("<g id=\"{PROBE}{}\"", texts.len());
        for a in ["transform", "style", "display", "visibility"] {
            if let Some(v) = n.attribute(a) {
                let _ =
                    std::fmt::Write::write_fmt(&mut g, format_args!(" {a}=\"{}\"", xml_escape(v)));
            }
        }
        g.push('>');
        for (x, y, _, _) in &lines {
            let _ = std::fmt::Write::write_fmt(
                &mut g,
                format_args!(
                    "<path d=\"M {x} {y} h 1 M {x} {y} v 1\" fill=\"none\" stroke=\"#000\"/>"
                ),
            );
        }
        g.push_str("</g>");
        out.push_str(&src[at..r.start]);
        out.push_str(&g);
        at = r.end;
        texts.push(TextInfo {
            name,
            lines: content,
            font_px: font_px(n),
        });
    }
    out.push_str(&src[at..]);
    (out, texts)
}

fn clip(s: &str, n: usize) -> String {
    let mut t: String = s.chars().take(n).collect();
    if s.chars().count() > n {
        t.push_str("...");
    }
    t
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
}

/// Most hatch segments a drawing may get, all shapes together (each shape
/// has its own cap in hatch.rs): a million lines are about 25 MB of G-code
/// and hours of drawing.
pub const MAX_HATCH_SEGMENTS: usize = 1_000_000;

struct Walker<'a> {
    opt: &'a SvgOptions,
    tol_px: f64,
    /// Page height (px), for flipping y.
    h: f64,
    layer_ids: Vec<(String, String)>,
    texts: Vec<TextInfo>,
    layers: Vec<Layer>,
    skipped: Vec<Skipped>,
    /// Index in `layers` of the Inkscape layer being walked.
    cur_layer: Option<usize>,
    /// Hatch segments made so far, all shapes together.
    hatch_segments: usize,
    arc_hints: ArcHints,
}

impl Walker<'_> {
    fn to_mm(&self, p: Pt) -> Pt {
        Pt::new(p.x * MM_PER_PX, (self.h - p.y) * MM_PER_PX)
    }

    fn layer(&mut self, name: &str) -> &mut Layer {
        let k = match self.layers.iter().position(|l| l.name == name) {
            Some(k) => k,
            None => {
                self.layers.push(Layer {
                    name: name.to_string(),
                    strokes: Vec::new(),
                });
                self.layers.len() - 1
            }
        };
        &mut self.layers[k]
    }

    fn walk(&mut self, g: &usvg::Group, ts: Transform) -> Result<()> {
        for node in g.children() {
            match node {
                usvg::Node::Group(c) => {
                    let ts = ts.pre_concat(c.transform());
                    if let Some(k) = c.id().strip_prefix(PROBE) {
                        let k: usize = k.parse().unwrap_or(usize::MAX);
                        self.text(c, ts, k)?;
                        continue;
                    }
                    let enter = self.opt.layers == LayerMode::Layers
                        && self.cur_layer.is_none()
                        && self.layer_ids.iter().any(|l| l.0 == c.id());
                    if enter {
                        let label = self
                            .layer_ids
                            .iter()
                            .find(|l| l.0 == c.id())
                            .map(|l| l.1.clone())
                            .unwrap_or_default();
                        self.layer(&label);
                        self.cur_layer = self.layers.iter().position(|l| l.name == label);
                        self.walk(c, ts)?;
                        self.cur_layer = None;
                    } else {
                        self.walk(c, ts)?;
                    }
                }
                usvg::Node::Path(p) if p.is_visible() => self.path(p, ts)?,
                usvg::Node::Image(im) => {
                    let s = im.size();
                    let r = [
                        (0.0, 0.0),
                        (s.width(), 0.0),
                        (s.width(), s.height()),
                        (0.0, s.height()),
                        (0.0, 0.0),
                    ];
                    let outline = vec![r
                        .iter()
                        .map(|&(x, y)| self.to_mm(map(ts, Point::from_xy(x, y))))
                        .collect()];
                    self.skipped.push(Skipped {
                        kind: SkipKind::Image,
                        name: name_or(if im.id().is_empty() { g.id() } else { im.id() }, "image"),
                        outline,
                    });
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The pass a path's strokes go to.
    fn pass_name(&self, p: &usvg::Path) -> String {
        match self.opt.layers {
            LayerMode::None => String::new(),
            LayerMode::Layers => self
                .cur_layer
                .and_then(|k| self.layers.get(k))
                .map(|l| l.name.clone())
                .unwrap_or_else(|| NO_LAYER.to_string()),
            LayerMode::ByColor => {
                let paint = p
                    .stroke()
                    .map(|s| s.paint())
                    .or_else(|| p.fill().map(|f| f.paint()));
                match paint {
                    Some(usvg::Paint::Color(c)) => {
                        format!("#{:02x}{:02x}{:02x}", c.red, c.green, c.blue)
                    }
                    Some(_) => "gradient or pattern".to_string(),
                    None => String::new(),
                }
            }
        }
    }

    fn path(&mut self, p: &usvg::Path, ts: Transform) -> Result<()> {
        let dots = p
            .stroke()
            .is_some_and(|s| s.linecap() != usvg::LineCap::Butt);
        // Control points first: a curve 1e13 px across would be flattened
        // into millions of points before the range check could refuse it.
        let ctrl: Stroke = p
            .data()
            .points()
            .iter()
            .map(|&q| self.to_mm(map(ts, q)))
            .collect();
        check_range(std::slice::from_ref(&ctrl), &name_or(p.id(), "path"))?;
        let mut strokes = Vec::new();
        flatten_path(p.data(), ts, self.tol_px, dots, &mut strokes);
        let mm: Vec<Stroke> = strokes
            .into_iter()
            .map(|s| s.into_iter().map(|q| self.to_mm(q)).collect())
            .collect();
        check_range(&mm, &name_or(p.id(), "path"))?;
        // What the pen draws: the flattened outline, or its curves as arcs (the
        // outline stays flat for hatching and for what is left out).
        let mut drawn = match self.opt.arcs {
            Some(tol) => self.arc_strokes(p.data(), ts, tol, dots),
            None => mm.clone(),
        };
        let has_area = mm.iter().any(|s| area(s).abs() > 1e-12);
        if let (Some(fill), true) = (p.fill(), has_area) {
            match self.opt.hatch {
                Some((spacing, angle)) => {
                    let rings: Vec<Stroke> = mm.iter().filter(|s| s.len() > 2).cloned().collect();
                    let rule = match fill.rule() {
                        usvg::FillRule::EvenOdd => FillRule::EvenOdd,
                        usvg::FillRule::NonZero => FillRule::NonZero,
                    };
                    let h = hatch(&rings, rule, spacing, angle)
                        .with_context(|| format!("hatching {}", name_or(p.id(), "path")))?;
                    self.hatch_segments +=
                        h.iter().map(|s| s.len().saturating_sub(1)).sum::<usize>();
                    if self.hatch_segments > MAX_HATCH_SEGMENTS {
                        bail!(
                            "hatching needs more than {MAX_HATCH_SEGMENTS} lines in all (reached at \
                             {}; about {} MB of G-code) at --hatch-spacing {spacing} mm: choose a \
                             larger spacing, or hatch fewer shapes",
                            name_or(p.id(), "path"),
                            MAX_HATCH_SEGMENTS * 25 / 1_000_000
                        );
                    }
                    drawn.extend(h);
                }
                None => {
                    let outline = mm.iter().filter(|s| s.len() > 2).cloned().collect();
                    self.skipped.push(Skipped {
                        kind: SkipKind::Fill,
                        name: name_or(p.id(), "path"),
                        outline,
                    });
                }
            }
        }
        let name = self.pass_name(p);
        self.layer(&name).strokes.extend(drawn);
        Ok(())
    }

    /// The path's subpaths in mm with its curves as arcs within `tol` (runs of
    /// cubics fitted together), the arcs recorded in `arc_hints`.
    fn arc_strokes(
        &mut self,
        data: &usvg::tiny_skia_path::Path,
        ts: Transform,
        tol: f64,
        dots: bool,
    ) -> Vec<Stroke> {
        let mm = |q: Point| self.to_mm(map(ts, q));
        let mut out = Vec::new();
        let mut cur: Stroke = Vec::new();
        let mut run: Vec<[Pt; 4]> = Vec::new();
        let mut start = Pt::new(0.0, 0.0);
        let mut hints = ArcHints::default();
        let flush = |cur: &mut Stroke, run: &mut Vec<[Pt; 4]>, hints: &mut ArcHints| {
            if let (None, Some(c)) = (cur.last(), run.first()) {
                cur.push(c[0]);
            }
            for seg in fit_cubics(run, tol) {
                let Some(&from) = cur.last() else { break };
                match seg {
                    Seg::Line(p) => cur.push(p),
                    Seg::Arc { to, centre, ccw } => {
                        hints.insert(from, to, centre, ccw);
                        cur.push(to);
                    }
                }
            }
            run.clear();
        };
        let finish = |cur: &mut Stroke, out: &mut Vec<Stroke>| {
            let mut s = std::mem::take(cur);
            s.dedup();
            if s.len() > 1 || (s.len() == 1 && dots) {
                out.push(s);
            }
        };
        for seg in data.segments() {
            let last = run
                .last()
                .map(|c| c[3])
                .or_else(|| cur.last().copied())
                .unwrap_or(start);
            match seg {
                PathSegment::QuadTo(c, p) => run.push(quad_as_cubic(last, mm(c), mm(p))),
                PathSegment::CubicTo(c1, c2, p) => run.push([last, mm(c1), mm(c2), mm(p)]),
                other => {
                    flush(&mut cur, &mut run, &mut hints);
                    match other {
                        PathSegment::MoveTo(p) => {
                            finish(&mut cur, &mut out);
                            start = mm(p);
                            cur.push(start);
                        }
                        PathSegment::LineTo(p) => cur.push(mm(p)),
                        PathSegment::Close if cur.last() != Some(&start) => cur.push(start),
                        _ => {}
                    }
                }
            }
        }
        flush(&mut cur, &mut run, &mut hints);
        finish(&mut cur, &mut out);
        self.arc_hints.extend(hints);
        out
    }

    /// A text probe: draws the text with the Hershey font when asked, else
    /// reports it.
    fn text(&mut self, g: &usvg::Group, ts: Transform, k: usize) -> Result<()> {
        let Some(info) = self.texts.get(k) else {
            return Ok(());
        };
        // Each probe path: M o, L o+x, M o, L o+y in the text's user space.
        let mut frames = Vec::new();
        for c in g.children() {
            if let usvg::Node::Path(p) = c {
                let pts: Vec<Pt> = p
                    .data()
                    .points()
                    .iter()
                    .map(|&q| self.to_mm(map(ts.pre_concat(p_ts(c)), q)))
                    .collect();
                if pts.len() >= 4 {
                    frames.push((pts[0], pts[1], pts[3]));
                }
            }
        }
        let font_px = info.font_px;
        let name = info.name.clone();
        let lines = info.lines.clone();
        let mut all = Vec::new();
        let mut outline = Vec::new();
        for ((o, ex, ey), (line, anchor)) in frames.iter().zip(&lines) {
            // Unit vectors of the text's user space on the page, in mm per px.
            let (ux, uy) = (
                Pt::new(ex.x - o.x, ex.y - o.y),
                Pt::new(ey.x - o.x, ey.y - o.y),
            );
            let layout = match &self.opt.text_font {
                Some(font) => Some(
                    crate::text::layout(line, 1.0, font)
                        .with_context(|| format!("drawing text {name}"))?,
                ),
                None => None,
            };
            // Width: the Hershey layout's, or about 0.6 em a character.
            let width = layout
                .as_ref()
                .map_or(line.chars().count() as f64 * 0.6, |l| l.width)
                * font_px;
            let shift = -anchor * width;
            let place = |u: f64, v: f64| {
                let u = u + shift;
                Pt::new(o.x + u * ux.x + v * uy.x, o.y + u * ux.y + v * uy.y)
            };
            outline.push(vec![
                place(0.0, 0.0),
                place(width, 0.0),
                place(width, -font_px),
                place(0.0, -font_px),
                place(0.0, 0.0),
            ]);
            if let Some(l) = layout {
                // Hershey layout in a box of font_px (y up, baseline 7/32 of
                // the box above its bottom) to the text's user space (y down).
                let base = 7.0 / 32.0;
                for s in l.strokes {
                    all.push(
                        s.iter()
                            .map(|q| place(q.x * font_px, -(q.y - base) * font_px))
                            .collect::<Stroke>(),
                    );
                }
            }
        }
        if self.opt.text_font.is_some() {
            check_range(&all, &name)?;
            let pass = match self.opt.layers {
                LayerMode::Layers => self
                    .cur_layer
                    .and_then(|k| self.layers.get(k))
                    .map(|l| l.name.clone())
                    .unwrap_or_else(|| NO_LAYER.to_string()),
                LayerMode::ByColor => "#000000".to_string(),
                LayerMode::None => String::new(),
            };
            self.layer(&pass).strokes.extend(all);
        } else {
            self.skipped.push(Skipped {
                kind: SkipKind::Text,
                name,
                outline,
            });
        }
        Ok(())
    }
}

/// Paths carry no transform of their own in usvg 0.45.
fn p_ts(_: &usvg::Node) -> Transform {
    Transform::identity()
}

/// Signed area of a ring (taken as closed).
fn area(s: &[Pt]) -> f64 {
    let n = s.len();
    (0..n)
        .map(|k| {
            let (a, b) = (s[k], s[(k + 1) % n]);
            a.x * b.y - b.x * a.y
        })
        .sum::<f64>()
        / 2.0
}

fn name_or(id: &str, what: &str) -> String {
    if id.is_empty() {
        format!("(unnamed {what})")
    } else {
        id.to_string()
    }
}

fn check_range(strokes: &[Stroke], name: &str) -> Result<()> {
    for p in strokes.iter().flatten() {
        if !(p.x.abs() <= MAX_MM && p.y.abs() <= MAX_MM) {
            bail!(
                "{name}: coordinate ({:.6e}, {:.6e}) mm is beyond +-{MAX_MM} mm; the file is \
                 broken or its units are wrong",
                p.x,
                p.y
            );
        }
    }
    Ok(())
}

fn map(ts: Transform, p: Point) -> Pt {
    let mut q = [p];
    ts.map_points(&mut q);
    Pt::new(q[0].x as f64, q[0].y as f64)
}

/// Flattens a path (px, transform applied). Subpaths of zero length are
/// dropped, or kept as a single point (a dot) when `dots` (round or square
/// caps, which SVG renders as a dot).
fn flatten_path(
    data: &usvg::tiny_skia_path::Path,
    ts: Transform,
    tol: f64,
    dots: bool,
    out: &mut Vec<Stroke>,
) {
    let mut cur: Stroke = Vec::new();
    let mut start = Pt::new(0.0, 0.0);
    let finish = |cur: &mut Stroke, out: &mut Vec<Stroke>| {
        let mut s = std::mem::take(cur);
        s.dedup();
        if s.len() > 1 || (s.len() == 1 && dots) {
            out.push(s);
        }
    };
    let mut open = false;
    for seg in data.segments() {
        match seg {
            PathSegment::MoveTo(p) => {
                if open {
                    finish(&mut cur, out);
                }
                start = map(ts, p);
                cur = vec![start];
                open = true;
            }
            PathSegment::LineTo(p) => cur.push(map(ts, p)),
            PathSegment::QuadTo(c, p) => {
                let p0 = *cur.last().unwrap_or(&start);
                flatten_cubic(quad_as_cubic(p0, map(ts, c), map(ts, p)), tol, &mut cur);
            }
            PathSegment::CubicTo(c1, c2, p) => {
                let p0 = *cur.last().unwrap_or(&start);
                flatten_cubic([p0, map(ts, c1), map(ts, c2), map(ts, p)], tol, &mut cur);
            }
            PathSegment::Close => {
                if cur.last() != Some(&start) {
                    cur.push(start);
                }
            }
        }
    }
    if open {
        finish(&mut cur, out);
    }
}

/// The quadratic Bézier p0-c-p3 as the cubic that draws the same curve (degree
/// elevation).
fn quad_as_cubic(p0: Pt, c: Pt, p3: Pt) -> [Pt; 4] {
    let towards = |a: Pt| Pt::new(a.x + 2.0 / 3.0 * (c.x - a.x), a.y + 2.0 / 3.0 * (c.y - a.y));
    [p0, towards(p0), towards(p3), p3]
}

/// Appends points (after the first) of a cubic flattened within `tol`.
/// The curve lies in the convex hull of its control points, so once both
/// inner control points are within `tol` of the chord, so is the curve; and
/// its length lies between the chord's and the control polygon's, so once
/// those agree within `LEN_TOL`, so does the length.
pub fn flatten_cubic(c: [Pt; 4], tol: f64, out: &mut Stroke) {
    flatten_rec(c, tol, out, 0);
}

fn flatten_rec(c: [Pt; 4], tol: f64, out: &mut Stroke, depth: u32) {
    let chord = c[0].dist(c[3]);
    let poly = c[0].dist(c[1]) + c[1].dist(c[2]) + c[2].dist(c[3]);
    if depth >= 16
        || !(poly.is_finite())
        || (dist_to_segment(c[1], c[0], c[3]) <= tol
            && dist_to_segment(c[2], c[0], c[3]) <= tol
            && poly - chord <= LEN_TOL * chord)
        || poly <= tol * 0.25
    {
        out.push(c[3]);
        return;
    }
    let mid = |a: Pt, b: Pt| Pt::new((a.x + b.x) / 2.0, (a.y + b.y) / 2.0);
    let (p01, p12, p23) = (mid(c[0], c[1]), mid(c[1], c[2]), mid(c[2], c[3]));
    let (p012, p123) = (mid(p01, p12), mid(p12, p23));
    let m = mid(p012, p123);
    flatten_rec([c[0], p01, p012, m], tol, out, depth + 1);
    flatten_rec([m, p123, p23, c[3]], tol, out, depth + 1);
}

/// Distance from `p` to the segment a-b.
pub fn dist_to_segment(p: Pt, a: Pt, b: Pt) -> f64 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    if len2 == 0.0 {
        return p.dist(a);
    }
    let t = (((p.x - a.x) * dx + (p.y - a.y) * dy) / len2).clamp(0.0, 1.0);
    p.dist(Pt::new(a.x + t * dx, a.y + t * dy))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{bounds, pen_down_length};

    fn dist_to_polyline(p: Pt, s: &[Pt]) -> f64 {
        s.windows(2)
            .map(|w| dist_to_segment(p, w[0], w[1]))
            .fold(f64::INFINITY, f64::min)
    }

    fn cubic_at(c: &[Pt; 4], t: f64) -> Pt {
        let u = 1.0 - t;
        let w = [u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t];
        Pt::new(
            (0..4).map(|i| w[i] * c[i].x).sum(),
            (0..4).map(|i| w[i] * c[i].y).sum(),
        )
    }

    /// A 100 x 100 mm page where one user unit is one millimetre.
    fn mm_page(body: &str) -> String {
        format!(
            r##"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink"
                 xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"
                 width="100mm" height="100mm" viewBox="0 0 100 100">{body}</svg>"##
        )
    }

    fn read(body: &str) -> Drawing {
        read_svg(mm_page(body).as_bytes(), &SvgOptions::default()).unwrap()
    }

    /// Asserts a stroke's points, given in SVG user units (y down), in mm.
    fn assert_pts(s: &Stroke, want: &[(f64, f64)]) {
        assert_eq!(s.len(), want.len(), "{s:?}");
        for (p, &(x, y)) in s.iter().zip(want) {
            let q = Pt::new(x, 100.0 - y);
            assert!(p.dist(q) < 1e-4, "got {p:?}, want {q:?} (all: {s:?})");
        }
    }

    #[test]
    fn cubic_flattening_stays_within_tolerance() {
        let c = [
            Pt::new(0.0, 0.0),
            Pt::new(10.0, 40.0),
            Pt::new(50.0, -30.0),
            Pt::new(60.0, 5.0),
        ];
        for tol in [1.0, 0.1, 0.01] {
            let mut s = vec![c[0]];
            flatten_cubic(c, tol, &mut s);
            assert_eq!(*s.last().unwrap(), c[3]);
            for k in 0..=2000 {
                let d = dist_to_polyline(cubic_at(&c, k as f64 / 2000.0), &s);
                assert!(d <= tol + 1e-9, "tol {tol}: {d}");
            }
            assert!(s.len() < 2000);
        }
    }

    #[test]
    fn shapes_and_transforms() {
        // 96 px = 25.4 mm. A 96x96 px page; a circle of r = 48 px at the
        // centre; a line moved by a translate; a rect as a closed stroke.
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="96" height="96">
            <circle cx="48" cy="48" r="48" fill="none" stroke="black"/>
            <g transform="translate(10 0)"><line x1="0" y1="0" x2="0" y2="96" stroke="black"/></g>
            <rect x="0" y="0" width="48" height="24" fill="none" stroke="black"/>
            <polyline points="0,0 10,10 20,0" fill="none" stroke="black"/>
            <ellipse cx="48" cy="48" rx="20" ry="10" fill="none" stroke="black"/>
            <path d="M 0 96 Q 48 0 96 96" fill="none" stroke="black"/>
        </svg>"#;
        let s = strokes_from_svg(svg, 0.01).unwrap();
        assert_eq!(s.len(), 6);
        let r = 12.7;
        for p in &s[0] {
            let d = p.dist(Pt::new(12.7, 12.7));
            assert!((d - r).abs() < 0.01 + 3e-4 * r, "{d}");
        }
        assert!(s[0].len() > 16);
        let line = &s[1];
        assert_eq!(line.len(), 2);
        let x = 10.0 * MM_PER_PX;
        assert!((line[0].x - x).abs() < 1e-4 && (line[0].y - 25.4).abs() < 1e-4);
        assert!((line[1].x - x).abs() < 1e-4 && line[1].y.abs() < 1e-4);
        assert_eq!(s[2].len(), 5);
        assert_eq!(s[2][0], s[2][4]);
        assert_eq!(s[3].len(), 3);
        let apex = Pt::new(48.0 * MM_PER_PX, 48.0 * MM_PER_PX);
        assert!(dist_to_polyline(apex, &s[5]) < 0.011);
    }

    #[test]
    fn clones_land_where_they_are_drawn() {
        let defs = r#"<defs><path id="p" d="M 0 0 L 10 0" stroke="black" fill="none"/></defs>"#;
        // translate: 40 mm right and down, once.
        let d = read(&format!(
            r##"{defs}<use xlink:href="#p" transform="translate(40,40)"/>"##
        ));
        assert_pts(&d.strokes()[0], &[(40.0, 40.0), (50.0, 40.0)]);
        // rotate(45): the line at 45 degrees, not 90.
        let d = read(&format!(
            r##"{defs}<use href="#p" transform="translate(50,50) rotate(45)"/>"##
        ));
        let h = 10.0 / 2f64.sqrt();
        assert_pts(&d.strokes()[0], &[(50.0, 50.0), (50.0 + h, 50.0 + h)]);
        // scale(2): 20 mm long, not 40.
        let d = read(&format!(
            r##"{defs}<use href="#p" transform="scale(2)" x="5" y="5"/>"##
        ));
        assert_pts(&d.strokes()[0], &[(10.0, 10.0), (30.0, 10.0)]);
        // A clone of a group that holds a clone, inside a transformed group.
        let d = read(&format!(
            r##"{defs}<defs><g id="g"><use href="#p" transform="translate(0,10)"/></g></defs>
            <g transform="translate(10,0)"><use href="#g" transform="translate(20,30)"/></g>"##
        ));
        assert_pts(&d.strokes()[0], &[(30.0, 40.0), (40.0, 40.0)]);
    }

    #[test]
    fn nested_svg_is_placed_once() {
        // A nested viewport at (20, 30), 40 x 40 user units showing a 10 x 10
        // viewBox: scale 4. The line (0,0)-(10,0) spans 20..60 at y = 30.
        let d = read(
            r#"<g transform="translate(5,5)"><svg x="20" y="30" width="40" height="40" viewBox="0 0 10 10">
                <line x1="0" y1="0" x2="10" y2="0" stroke="black"/></svg></g>"#,
        );
        assert_pts(&d.strokes()[0], &[(25.0, 35.0), (65.0, 35.0)]);
        // The same nested svg used as a clone with a translate.
        let d = read(
            r##"<defs><svg id="s" width="40" height="40" viewBox="0 0 10 10">
                <line x1="0" y1="0" x2="10" y2="0" stroke="black"/></svg></defs>
                <use href="#s" transform="translate(10,20)"/>"##,
        );
        assert_pts(&d.strokes()[0], &[(10.0, 20.0), (50.0, 20.0)]);
    }

    #[test]
    fn svgz_reads_like_svg() {
        use std::io::Write;
        let svg = mm_page(r#"<line x1="1" y1="2" x2="3" y2="4" stroke="black"/>"#);
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(svg.as_bytes()).unwrap();
        let z = gz.finish().unwrap();
        let a = read_svg(svg.as_bytes(), &SvgOptions::default()).unwrap();
        let b = read_svg(&z, &SvgOptions::default()).unwrap();
        assert_eq!(a, b);
        assert_pts(&b.strokes()[0], &[(1.0, 2.0), (3.0, 4.0)]);
        assert!(read_svg(&z[..z.len() / 2], &SvgOptions::default()).is_err());
        assert!(read_svg(&[0xff, 0xfe, 0], &SvgOptions::default()).is_err());
    }

    #[test]
    fn what_cannot_be_drawn_is_named() {
        let d = read(
            r#"<text id="title" x="10" y="20" font-size="5">Hello</text>
               <image id="photo" x="0" y="0" width="10" height="10" href="data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="/>
               <rect id="box" x="50" y="50" width="10" height="10" fill="red"/>
               <line x1="0" y1="0" x2="5" y2="0" stroke="black"/>"#,
        );
        let names: Vec<(SkipKind, &str)> = d
            .skipped
            .iter()
            .map(|s| (s.kind, s.name.as_str()))
            .collect();
        assert!(
            names.contains(&(SkipKind::Text, "title \"Hello\"")),
            "{names:?}"
        );
        assert!(names.contains(&(SkipKind::Image, "photo")), "{names:?}");
        assert!(names.contains(&(SkipKind::Fill, "box")), "{names:?}");
        // The text's outline starts at its anchor (10, 20).
        let t = d.skipped.iter().find(|s| s.kind == SkipKind::Text).unwrap();
        assert!(
            t.outline[0][0].dist(Pt::new(10.0, 80.0)) < 1e-4,
            "{:?}",
            t.outline
        );
        // The filled box's outline is still drawn, and the line.
        assert_eq!(d.strokes().len(), 2);
    }

    #[test]
    fn text_drawn_with_hershey_sits_on_its_baseline() {
        let svg = mm_page(
            r#"<g transform="translate(10,0)"><text x="10" y="50" style="font-size:10px">HI</text></g>"#,
        );
        let opt = SvgOptions {
            text_font: Some("futural".into()),
            ..SvgOptions::default()
        };
        let d = read_svg(svg.as_bytes(), &opt).unwrap();
        assert!(d.skipped.is_empty());
        let s = d.strokes();
        let want = crate::text::layout("HI", 1.0, "futural")
            .unwrap()
            .strokes
            .len();
        assert_eq!(s.len(), want);
        let (lo, hi) = bounds(&s).unwrap();
        // Baseline at y = 50 (page y 50 up), cap height 21/32 of the 10 mm box.
        assert!((lo.y - 50.0).abs() < 1e-4, "{lo:?}");
        assert!((hi.y - lo.y - 21.0 / 32.0 * 10.0).abs() < 1e-4, "{hi:?}");
        assert!(lo.x > 20.0 && hi.x < 40.0, "{lo:?} {hi:?}");
        // Centred (Inkscape's text-anchor in the style): the middle of the
        // layout's advance on x = 50.
        let svg =
            mm_page(r#"<text x="50" y="50" style="font-size:10px;text-anchor:middle">HI</text>"#);
        let c = read_svg(svg.as_bytes(), &opt).unwrap().strokes();
        let (clo, chi) = bounds(&c).unwrap();
        let w = crate::text::layout("HI", 10.0, "futural").unwrap().width;
        assert!(
            (clo.x - (lo.x - 20.0 + 50.0 - w / 2.0)).abs() < 1e-3,
            "{clo:?} {w}"
        );
        assert!(
            (chi.x - (hi.x - 20.0 + 50.0 - w / 2.0)).abs() < 1e-3,
            "{chi:?}"
        );
    }

    #[test]
    fn zero_length_lines_are_not_dots_unless_capped_round() {
        let d = read(
            r#"<line x1="5" y1="5" x2="5" y2="5" stroke="black"/>
               <path d="M 10 10 L 10 10 Z" stroke="black"/>"#,
        );
        assert!(d.strokes().is_empty(), "{:?}", d.strokes());
        let d =
            read(r#"<line x1="5" y1="5" x2="5" y2="5" stroke="black" stroke-linecap="round"/>"#);
        let s = d.strokes();
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].len(), 1);
        assert!(s[0][0].dist(Pt::new(5.0, 95.0)) < 1e-4);
    }

    #[test]
    fn tiny_circles_keep_their_length() {
        // r = 0.3 mm: a 0.05 mm tolerance alone allows an octagon (-2.6 %).
        let d = read(r#"<circle cx="10" cy="10" r="0.3" fill="none" stroke="black"/>"#);
        let len = pen_down_length(&d.strokes());
        let want = std::f64::consts::TAU * 0.3;
        assert!((len - want).abs() / want < 0.002, "{len} vs {want}");
        // A large one stays within 0.1 % too, without excessive points.
        let d = read(r#"<circle cx="50" cy="50" r="45" fill="none" stroke="black"/>"#);
        let s = d.strokes();
        let want = std::f64::consts::TAU * 45.0;
        assert!((pen_down_length(&s) - want).abs() / want < 0.001);
        assert!(s[0].len() < 400, "{}", s[0].len());
    }

    #[test]
    fn deep_nesting_is_refused_not_a_crash() {
        for n in [300, 50_000] {
            let svg = mm_page(&format!(
                "{}<path d=\"M 0 0 L 1 1\" stroke=\"black\"/>{}",
                "<g transform=\"translate(0.001,0)\">".repeat(n),
                "</g>".repeat(n)
            ));
            let e = read_svg(svg.as_bytes(), &SvgOptions::default()).unwrap_err();
            assert!(format!("{e:#}").contains("nested deeper than 256"), "{e:#}");
        }
        // Markup that is not nesting does not count: comments, CDATA, a
        // doctype with entities, quoted '>', self-closing tags.
        let g300 = "<g>".repeat(300);
        let fake = format!(
            "<!DOCTYPE svg [<!ENTITY e \"<g>\">]><svg><!--{g300}--><![CDATA[{g300}]]>{}<g id=\"a>b\">{}</g></svg>",
            "<path/>".repeat(300),
            "<g/>".repeat(300)
        );
        assert_eq!(nesting_beyond(&fake, 2), None);
        assert_eq!(nesting_beyond("<a><b><c/></b></a>", 1), Some(2));
        // 200 levels are fine and each translate counts.
        let svg = mm_page(&format!(
            "{}<path d=\"M 0 0 L 1 1\" stroke=\"black\"/>{}",
            "<g transform=\"translate(0.1,0)\">".repeat(200),
            "</g>".repeat(200)
        ));
        let d = read_svg(svg.as_bytes(), &SvgOptions::default()).unwrap();
        assert!((d.strokes()[0][0].x - 20.0).abs() < 1e-3);
    }

    #[test]
    fn numbers_beyond_any_drawing_are_refused_before_usvg() {
        assert_eq!(huge_number("M 1,2 L 3e5-4e2"), None);
        assert_eq!(huge_number("M1-1E39-8.39"), Some(-1e39));
        assert_eq!(huge_number("scale(1e300)"), Some(1e300));
        assert_eq!(huge_number("x1e999"), Some(f64::INFINITY));
        // Colours with an 'e' among hex digits are not numbers to check.
        let d = read(r##"<path id="c" d="M 0 0 H 5" stroke="#2e5566" fill="#1e4000"/>"##);
        assert_eq!(d.strokes().len(), 1);
        // An arc to 1e39 px once made svgtypes build segments without end.
        let svg = mm_page(
            r#"<path id="wild" d="M 0 0 C 1 1 2 2 1e39 3 A 5 5 0 0 0 10 10" stroke="black"/>"#,
        );
        let e = read_svg(svg.as_bytes(), &SvgOptions::default()).unwrap_err();
        assert!(format!("{e:#}").contains("wild d="), "{e:#}");
        // An arc of radius 1e20 px, refused at its control points, quickly.
        let t = std::time::Instant::now();
        let svg = mm_page(r#"<path id="big" d="M 0 0 A 1e20 1e20 0 1 0 1e20 1" stroke="black"/>"#);
        let e = read_svg(svg.as_bytes(), &SvgOptions::default()).unwrap_err();
        assert!(format!("{e:#}").contains("big"), "{e:#}");
        assert!(t.elapsed().as_secs_f64() < 2.0, "{:?}", t.elapsed());
    }

    #[test]
    fn absurd_coordinates_are_refused_by_name() {
        let err = read_svg(
            mm_page(r#"<line id="far" x1="0" y1="0" x2="1e17" y2="0" stroke="black"/>"#).as_bytes(),
            &SvgOptions::default(),
        )
        .unwrap_err();
        assert!(format!("{err:#}").contains("far"), "{err:#}");
    }

    #[test]
    fn layers_and_colours_make_passes() {
        let body = r##"<g inkscape:groupmode="layer" id="layer1" inkscape:label="Red pen">
              <line x1="0" y1="0" x2="10" y2="0" stroke="#ff0000"/>
              <g inkscape:groupmode="layer" id="sub"><line x1="0" y1="5" x2="10" y2="5" stroke="#0000ff"/></g>
            </g>
            <g inkscape:groupmode="layer" id="layer2" inkscape:label="Black">
              <line x1="0" y1="10" x2="10" y2="10" stroke="#000000"/>
            </g>"##;
        let d = read(body);
        let names: Vec<&str> = d.layers.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, ["Red pen", "Black"]);
        assert_eq!(
            d.layers[0].strokes.len(),
            2,
            "sublayers belong to their layer"
        );
        let by = read_svg(
            mm_page(body).as_bytes(),
            &SvgOptions {
                layers: LayerMode::ByColor,
                ..SvgOptions::default()
            },
        )
        .unwrap();
        let names: Vec<&str> = by.layers.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, ["#ff0000", "#0000ff", "#000000"]);
    }

    #[test]
    fn hatching_has_a_total_cap_with_a_clear_error() {
        // Twelve squares of 50 mm at 0.0005 mm: 100,000 lines each, under the
        // cap of one shape, 1.2 million in all.
        let body: String = (0..12)
            .map(|k| {
                format!(
                    r#"<rect id="r{k}" x="{}" y="{}" width="50" height="50"/>"#,
                    k % 2 * 50,
                    k / 2 * 8
                )
            })
            .collect();
        let opt = |spacing| SvgOptions {
            hatch: Some((spacing, 0.0)),
            ..SvgOptions::default()
        };
        let Err(e) = read_svg(mm_page(&body).as_bytes(), &opt(0.0005)) else {
            panic!("1.2 million hatch lines")
        };
        let e = format!("{e:#}");
        assert!(
            e.contains("more than 1000000 lines in all") && e.contains("larger spacing"),
            "{e}"
        );
        // At 0.5 mm the same drawing hatches.
        assert!(read_svg(mm_page(&body).as_bytes(), &opt(0.5)).is_ok());
    }

    #[test]
    fn hatching_follows_the_fill_rule() {
        // A 20 mm square with a 10 mm square hole (same winding): even-odd
        // leaves the hole empty.
        let body = r#"<path id="frame" fill-rule="evenodd" fill="black"
            d="M 10 10.5 H 30 V 30.5 H 10 Z M 15 15.5 H 25 V 25.5 H 15 Z"/>"#;
        let d = read_svg(
            mm_page(body).as_bytes(),
            &SvgOptions {
                hatch: Some((1.0, 0.0)),
                ..SvgOptions::default()
            },
        )
        .unwrap();
        assert!(d.skipped.is_empty());
        let s = d.strokes();
        // Two outlines, then hatching; no hatch point strictly inside the hole.
        for p in s[2..].iter().flatten() {
            let inside_hole =
                p.x > 15.0 + 1e-6 && p.x < 25.0 - 1e-6 && p.y > 74.5 + 1e-6 && p.y < 84.5 - 1e-6;
            assert!(!inside_hole, "{p:?}");
        }
        // 20 lines of which 10 cross the hole: 10 x 20 + 10 x 10 = 300 mm of hatch.
        let hatch_len: f64 = s[2..]
            .iter()
            .flat_map(|s| s.windows(2))
            .filter(|w| (w[0].y - w[1].y).abs() < 1e-9)
            .map(|w| w[0].dist(w[1]))
            .sum();
        assert!((hatch_len - 300.0).abs() < 1e-3, "{hatch_len}");
        assert!(s.len() - 2 <= 4, "{} hatch strokes", s.len() - 2);
    }
}
