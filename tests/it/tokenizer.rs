//! pbrt's tokenizer tests (reference §5.3) and number parsing.

use crate::common::scene;
use pbrt_sppm::parser::lexer::{decode_string, tokenize_all};

#[test]
fn tokenizer_basics() {
    assert_eq!(
        tokenize_all(br#"Shape "sphere" "float radius" [1]"#).unwrap(),
        ["Shape", "\"sphere\"", "\"float radius\"", "[", "1", "]"]
    );
    // A newline between tokens changes nothing.
    assert_eq!(
        tokenize_all(b"Shape \"sphere\"\n\"float radius\" [1]").unwrap(),
        tokenize_all(br#"Shape "sphere" "float radius" [1]"#).unwrap()
    );
}

#[test]
fn comments_glued_words_and_escapes() {
    let toks = tokenize_all(b"Shape\"sphere\" # foo bar [\n\"float radius\\\"\" 1").unwrap();
    assert_eq!(toks, ["Shape", "\"sphere\"", "# foo bar [", "\"float radius\\\"\"", "1"]);
    assert_eq!(decode_string(toks[3].as_bytes()), "float radius\"");
    assert_eq!(tokenize_all(b"[1 2]x").unwrap(), ["[", "1", "2", "]", "x"]);
    // '#' only starts a comment where a token starts.
    assert_eq!(tokenize_all(b"1#x 2").unwrap(), ["1#x", "2"]);
    assert_eq!(tokenize_all(b"a\r\n# c\rb").unwrap(), ["a", "# c", "b"]);
}

#[test]
fn tokenizer_errors() {
    let e = tokenize_all(b"\"float radius").unwrap_err();
    assert!(e.message.contains("premature EOF"), "{e:?}");
    let e = tokenize_all(b"\"float radius\\").unwrap_err();
    assert!(e.message.contains("premature EOF"), "{e:?}");
    let e = tokenize_all(b"\"float\nradius\"").unwrap_err();
    assert!(e.message.contains("unterminated string"), "{e:?}");
    assert_eq!(e.offset, 6);
}

#[test]
fn tokenize_file() {
    let toks = tokenize_all(b"WorldBegin # hello\nIntegrator \"deep\" \"float density\" [ 2 2.66612 -5e-51]").unwrap();
    assert_eq!(
        toks,
        ["WorldBegin", "# hello", "Integrator", "\"deep\"", "\"float density\"", "[", "2", "2.66612", "-5e-51", "]"]
    );
}

#[test]
fn numbers_are_rounded_once_from_the_decimal_text() {
    // Just above the midpoint between 1 and the next f32: correct rounding goes up,
    // rounding through f64 first would land exactly on the midpoint and go to 1.
    let s = scene(r#"WorldBegin Shape "sphere" "float radius" 1.00000005960464477539062501"#);
    let pbrt_sppm::scene::Geometry::Quadric(pbrt_sppm::shapes::Quadric::Sphere(sp)) = &s.shapes[0].geometry else {
        panic!("not a sphere")
    };
    assert_eq!(sp.radius, 1.0000001f32);
    assert_ne!(sp.radius, 1.0);
    let s = scene(r#"WorldBegin Shape "sphere" "float radius" [ .25 ] "float zmin" -2.5e-1 "float zmax" +0.25"#);
    let pbrt_sppm::scene::Geometry::Quadric(pbrt_sppm::shapes::Quadric::Sphere(sp)) = &s.shapes[0].geometry else {
        panic!("not a sphere")
    };
    assert_eq!((sp.radius, sp.z_min, sp.z_max), (0.25, -0.25, 0.25));
}

#[test]
fn float_written_integers_are_truncated_with_a_warning() {
    let s = scene(r#"WorldBegin Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2.0]"#);
    assert_eq!(s.meshes[0].indices, [0, 1, 2]);
    let w = &s.warnings[0];
    assert_eq!((w.line, w.column), (1, 87));
    assert!(w.message.contains("2.0 is not an integer"), "{}", w.message);
}

#[test]
fn every_parameter_type_and_alias_parses() {
    let s = scene(
        r#"WorldBegin Shape "sphere"
        "integer a" [1 -2] "float b" 1.5 "point2 c" [1 2] "vector2 d" [1 2] "point3 e" [1 2 3]
        "vector3 f" [1 2 3] "normal g" [0 0 1] "normal3 h" [0 0 1] "bool i" "true" "bool j" false
        "string k" "x" "texture l" "t" "rgb m" [1 1 1] "spectrum n" [400 1 500 2] "spectrum o" "metal-Au-eta"
        "blackbody p" [5500] "point q" [1 2 3] "vector r" [1 2 3] "color s" [1 1 1] "xyz t" [1 1 1] "float u" []"#,
    );
    let types: Vec<String> = s
        .warnings
        .iter()
        .map(|w| w.message.trim_start_matches("parameter \"").split(' ').next().unwrap_or("").to_string())
        .collect();
    assert_eq!(
        types,
        [
            "integer",
            "float",
            "point2",
            "vector2",
            "point3",
            "vector3",
            "normal",
            "normal3",
            "bool",
            "bool",
            "string",
            "texture",
            "rgb",
            "spectrum",
            "spectrum",
            "blackbody",
            "point",
            "vector",
            "color",
            "xyz",
            "float"
        ]
    );
}

#[test]
fn errors_show_the_source_line_and_a_caret() {
    let e = crate::common::load("WorldBegin\n\tShape \"sphere\" \"float radius\" [ x ]\n").unwrap_err();
    assert_eq!(
        e.with_source(),
        "tests/data/good/inline.pbrt:2:34: error: \"float radius\": expected a number, found 'x'\n  \
         \tShape \"sphere\" \"float radius\" [ x ]\n  \t                                ^"
    );
}

/// A mesh list long enough for the parallel reader (over 1 MB of text), with numbers in
/// every form the fast path and the exact path take, and mixed whitespace.
fn long_mesh(n: usize, tail: &str) -> (String, Vec<[f32; 3]>) {
    let forms = ["{}", "+{}", "{}e0", "{}E-0", "{}\t", "{}\r\n"];
    let (mut text, mut expect) = (String::from("WorldBegin Shape \"trianglemesh\" \"point3 P\" [\n"), Vec::new());
    for i in 0..n {
        let v = [i as f32 * 0.001, -(i as f32) * 0.25, 1.0 / (1 + i) as f32];
        for (k, x) in v.iter().enumerate() {
            let form = forms[(i + k) % forms.len()].replace("+{}", if x.is_sign_negative() { "{}" } else { "+{}" });
            text += &form.replace("{}", &format!("{x}"));
            text.push(' ');
        }
        expect.push(v);
    }
    text += tail;
    text += "] \"integer indices\" [0 1 2]\n";
    (text, expect)
}

#[test]
fn long_number_lists_read_in_parallel_pieces_match_the_sequential_reader() {
    let (text, _) = long_mesh(60_000, "");
    assert!(text.len() > 1 << 20, "the list must take the parallel path");
    let s = scene(&text);
    // A comment in the list sends the whole list through the sequential reader.
    let (seq, _) = long_mesh(60_000, "# the sequential reader\n");
    let s_seq = scene(&seq);
    assert_eq!(s.meshes[0].p.len(), 60_000);
    let bits = |p: &[[f32; 3]]| p.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&s.meshes[0].p), bits(&s_seq.meshes[0].p));
    let (_, expect) = long_mesh(60_000, "");
    assert_eq!(bits(&s.meshes[0].p), bits(&expect));
}

#[test]
fn a_bad_number_deep_in_a_long_list_is_reported_at_its_line_and_column() {
    let (mut text, _) = long_mesh(60_000, "");
    let at = text.len() / 2;
    let at = at + text[at..].find(' ').unwrap_or(0);
    text.insert_str(at, " 1.5x");
    let line = 1 + text[..at].matches('\n').count();
    let column = at - text[..at].rfind('\n').map_or(0, |k| k + 1) + 2;
    let e = crate::common::load(&text).unwrap_err().to_string();
    assert!(e.contains(&format!(":{line}:{column}: error:")), "{e}");
    assert!(e.contains("expected a number, found '1.5x'"), "{e}");
}
