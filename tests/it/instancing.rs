//! 25,000 instances of one 30,000-triangle mesh load in about the memory of one copy.
//! (Their load time is measured by `pbrt-bench`, not here.)

use pbrt_sppm::scene::{LoadOptions, load_scene};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// Counts the bytes allocated by the current thread (each test runs on its own thread,
/// and scene loading is single-threaded), so concurrent tests do not disturb it.
struct Counting;

thread_local! {
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn track(delta: isize) {
    let _ = LIVE.try_with(|l| {
        l.set(l.get() + delta);
        let _ = PEAK.try_with(|p| p.set(p.get().max(l.get())));
    });
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        track(layout.size() as isize);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        track(-(layout.size() as isize));
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        track(new_size as isize - layout.size() as isize);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A binary PLY grid with `n × n` quads (2n² triangles).
fn write_grid_ply(path: &std::path::Path, n: usize) {
    let nv = (n + 1) * (n + 1);
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        2 * n * n
    )
    .into_bytes();
    for j in 0..=n {
        for i in 0..=n {
            for c in [i as f32 / n as f32, j as f32 / n as f32, ((i * j) % 7) as f32 * 1e-3] {
                b.extend(c.to_le_bytes());
            }
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = |di: usize, dj: usize| ((j + dj) * (n + 1) + i + di) as i32;
            for tri in [[v(0, 0), v(1, 0), v(1, 1)], [v(0, 0), v(1, 1), v(0, 1)]] {
                b.push(3);
                tri.iter().for_each(|x| b.extend(x.to_le_bytes()));
            }
        }
    }
    std::fs::write(path, b).unwrap();
}

/// Past a few thousand instances, room for the rest of the file's is reserved at once
/// (counted from the `ObjectInstance` words ahead, a comment's too) rather than grown
/// by doubling, which copied every record into fresh pages; every record is kept.
#[test]
fn instance_records_are_reserved_once() {
    let dir = crate::common::Scratch::new("inst-room");
    let mut scene = String::from("WorldBegin\nObjectBegin \"s\"\nShape \"sphere\"\nObjectEnd\n");
    let n = 10_000;
    for k in 0..n {
        scene.push_str(&format!("AttributeBegin Translate {k} 0 0 ObjectInstance \"s\" AttributeEnd\n"));
    }
    scene.push_str("# ObjectInstance \"s\" (a comment)\n");
    let path = dir.join("room.pbrt");
    std::fs::write(&path, &scene).unwrap();
    let s = load_scene(&path, &LoadOptions::default()).expect("loads");
    assert_eq!(s.instances.len(), n);
    // At the 4,096th the rest (and the comment's word) are counted; doubling would
    // leave room for 16,384.
    assert_eq!(s.instances.capacity(), n + 1, "the instances ahead and the comment's word");
    for k in [0, 4095, 4096, 4097, n - 1] {
        assert_eq!(s.instances.get(k).world_from_instance().w_axis.x, k as f64);
    }
}

#[test]
fn many_instances_cost_about_one_copy() {
    let dir = crate::common::Scratch::new("inst");
    write_grid_ply(&dir.join("grid.ply"), 123); // 30,258 triangles
    let mut scene =
        String::from("WorldBegin\nObjectBegin \"g\"\nShape \"plymesh\" \"string filename\" \"grid.ply\"\nObjectEnd\n");
    for k in 0..25_000 {
        let (x, z) = (k % 160, k / 160);
        scene.push_str(&format!(
            "AttributeBegin\nTranslate {x} 0 {z}\nRotate {} 0 1 0\nObjectInstance \"g\"\nAttributeEnd\n",
            k % 360
        ));
    }
    let path = dir.join("many.pbrt");
    std::fs::write(&path, &scene).unwrap();

    let before = LIVE.with(Cell::get);
    PEAK.with(|p| p.set(before));
    let s = load_scene(&path, &LoadOptions::default()).expect("loads");
    let peak = PEAK.with(Cell::get) - before;

    assert_eq!(s.meshes.len(), 1, "the mesh is stored once");
    assert_eq!(s.instances.len(), 25_000);
    assert_eq!(s.objects[0].shapes.len(), 1);
    let one_copy = s.meshes[0].heap_bytes() as isize;
    assert_eq!(s.meshes[0].triangle_count(), 30_258);
    // One copy is ~0.5 MB; 25,000 copies would be ~12 GB. Allow the mesh a few times
    // over (reading buffers), the 1.5 MB scene text and 25,000 transforms.
    let budget = 4 * one_copy + 3 * scene.len() as isize + 25_000 * 512;
    assert!(peak < budget, "peak {peak} bytes while loading; budget {budget}");
    let counts = &pbrt_sppm::cli::check::report(&s, false)["counts"];
    assert_eq!(counts["triangles"], 30_258u64 * 25_000);
}

/// pbrt-v3 reports an instance of an undefined object and goes on without it;
/// pbrt-v4 stops. The defined object's instances still place it.
#[test]
fn a_v3_instance_of_an_undefined_object_is_left_out_with_a_warning() {
    let body = |film: &str| {
        format!(
            "{film}\nWorldBegin\nObjectInstance \"zz\"\nObjectBegin \"ball\"\nShape \"sphere\"\nObjectEnd\n\
             Translate 5 0 0\nObjectInstance \"ball\"\nObjectInstance \"zz\"\nWorldEnd\n"
        )
    };
    let s = crate::common::scene(&body("Film \"image\""));
    let w: Vec<String> = crate::common::warnings(&s).into_iter().filter(|m| m.contains("\"zz\"")).collect();
    assert_eq!(w.len(), 1, "one warning a name: {w:?}");
    assert!(w[0].contains("left out"), "{w:?}");
    let placed: Vec<(usize, f64)> = (0..s.instances.len())
        .map(|k| s.instances.get(k))
        .map(|p| (s.objects[p.object() as usize].shapes.len(), p.world_from_instance().w_axis.x))
        .collect();
    assert_eq!(placed.iter().filter(|(n, _)| *n > 0).collect::<Vec<_>>(), [&(1, 5.0)], "{placed:?}");
    let e = crate::common::load(&body("Film \"rgb\"")).expect_err("pbrt-v4 stops").to_string();
    assert!(e.contains(":3:1: error: object \"zz\" is not defined"), "{e}");
}

/// pbrt-v3 reports object statements out of place and goes on: an `ObjectInstance`
/// inside a definition is ignored, a nested `ObjectBegin` ends the definition before
/// it (what follows its `ObjectEnd` is world geometry), and an `ObjectEnd` outside
/// one ends an attribute block (or nothing). pbrt-v4 stops at each.
#[test]
fn v3_object_statements_out_of_place_go_on_as_pbrt_v3_goes_on() {
    let body = |film: &str| {
        format!(
            "{film}\nWorldBegin\nObjectBegin \"a\"\nShape \"sphere\" \"float radius\" 1\nObjectInstance \"a\"\n\
             ObjectBegin \"b\"\nShape \"sphere\" \"float radius\" 2\nObjectEnd\nShape \"sphere\" \"float radius\" 3\n\
             ObjectEnd\nObjectEnd\nAttributeBegin\nTranslate 5 0 0\nObjectEnd\nObjectEnd\nObjectInstance \"a\"\n\
             ObjectInstance \"b\"\nWorldEnd\n"
        )
    };
    let s = crate::common::scene(&body("Film \"image\""));
    let radius = |d: &pbrt_sppm::scene::ShapeDesc| match &d.geometry {
        pbrt_sppm::scene::Geometry::Quadric(pbrt_sppm::shapes::Quadric::Sphere(s)) => s.radius,
        other => panic!("{other:?}"),
    };
    let objects: Vec<(&str, Vec<f32>)> =
        s.objects.iter().map(|o| (o.name.as_str(), o.shapes.iter().map(radius).collect())).collect();
    assert_eq!(objects, [("a", vec![1.0]), ("b", vec![2.0])]);
    assert_eq!(s.shapes.iter().map(radius).collect::<Vec<_>>(), [3.0], "after b's ObjectEnd: the world");
    // The AttributeBegin's Translate ended at the ObjectEnd: both instances at the origin.
    let at: Vec<f64> = (0..s.instances.len()).map(|k| s.instances.get(k).world_from_instance().w_axis.x).collect();
    assert_eq!(at, [0.0, 0.0]);
    let w: Vec<String> = crate::common::warnings(&s).into_iter().filter(|m| m.contains("pbrt-v3")).collect();
    let expected = [
        "ObjectInstance is not allowed inside an object definition; ignored",
        "ObjectBegin inside another object definition; that definition ends here",
        "ObjectEnd without ObjectBegin; it ends an attribute block", // a's ObjectBegin
        "ObjectEnd without ObjectBegin; ignored",
        "ObjectEnd without ObjectBegin; it ends an attribute block", // the AttributeBegin
        "ObjectEnd without ObjectBegin; ignored",
    ];
    assert_eq!(w.len(), expected.len(), "{w:?}");
    for (w, want) in w.iter().zip(expected) {
        assert!(w.contains(want), "{w} lacks {want}");
    }
    let e = crate::common::load(&body("Film \"rgb\"")).expect_err("pbrt-v4 stops").to_string();
    assert!(e.contains(":5:1: error: ObjectInstance is not allowed inside an object definition"), "{e}");
}

/// pbrt-v3's `ObjectEnd` inside an `AttributeBegin` of the definition ends the
/// definition and closes that block (its `ObjectEnd` includes an `AttributeEnd`); the
/// next `AttributeEnd` closes the `ObjectBegin`'s. Measured against pbrt-v3: the same
/// image as the file with the statements in their places. pbrt-v4 stops.
#[test]
fn a_v3_object_end_inside_an_attribute_block_closes_that_block_as_pbrt_v3_does() {
    let body = |film: &str| {
        format!(
            "{film}\nWorldBegin\nObjectBegin \"a\"\nMaterial \"mirror\"\nAttributeBegin\nTranslate 1 0 0\n\
             Shape \"sphere\" \"float radius\" 1\nObjectEnd\nShape \"sphere\" \"float radius\" 2\nAttributeEnd\n\
             Shape \"sphere\" \"float radius\" 3\nObjectInstance \"a\"\n"
        )
    };
    let s = crate::common::scene(&body("Film \"image\""));
    let radius = |d: &pbrt_sppm::scene::ShapeDesc| match &d.geometry {
        pbrt_sppm::scene::Geometry::Quadric(pbrt_sppm::shapes::Quadric::Sphere(s)) => s.radius,
        other => panic!("{other:?}"),
    };
    assert_eq!(s.objects.len(), 1);
    assert_eq!(s.objects[0].shapes.iter().map(radius).collect::<Vec<_>>(), [1.0]);
    assert_eq!(s.objects[0].shapes[0].object_to_world.w_axis.x, 1.0, "the block's Translate");
    assert_eq!(s.shapes.iter().map(radius).collect::<Vec<_>>(), [2.0, 3.0], "after ObjectEnd: the world");
    // Radius 2: the definition's state before its AttributeBegin (the mirror, no
    // Translate); radius 3: the state before ObjectBegin.
    let (two, three) = (&s.shapes[0], &s.shapes[1]);
    assert_eq!(two.object_to_world.w_axis.x, 0.0);
    assert_eq!(s.materials[two.material as usize].ty, "mirror");
    assert_eq!(s.materials[three.material as usize].ty, "matte");
    assert_eq!(s.instances.len(), 1);
    let w = crate::common::warnings(&s);
    assert!(
        w.iter().any(|m| m.contains("ObjectEnd inside an unclosed AttributeBegin") && m.contains("pbrt-v3")),
        "{w:?}"
    );
    let e = crate::common::load(&body("Film \"rgb\"")).expect_err("pbrt-v4 stops").to_string();
    assert!(e.contains(":8:1: error: ObjectEnd inside an unclosed AttributeBegin"), "{e}");
}
