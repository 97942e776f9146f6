//! Every integration test of `spu-tools` in one test binary: each `.rs` file beside this one is a
//! module of it, so the build links one test binary instead of one per file
//! (`tests/tests/test_files.rs` checks that none is left out).

mod animate_cli;
mod cli;
mod exit_status;
mod ext_cli;
mod ld_archives;
mod ld_overlays;
mod paper;
mod ppe_run;
mod run_input;
mod runtime_lib;
mod sched_cli;
mod shade_cli;
mod support;
mod threads_cli;
mod views;

/// The size and 8-bit RGB pixels of a PNG file the `spu` command wrote.
pub fn read_png_rgb(path: impl AsRef<std::path::Path>) -> (u32, u32, Vec<[u8; 3]>) {
    let path = path.as_ref();
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut bytes = vec![0; reader.output_buffer_size().expect("a PNG of a sane size")];
    let info = reader.next_frame(&mut bytes).unwrap();
    assert_eq!(
        (info.color_type, info.bit_depth),
        (png::ColorType::Rgb, png::BitDepth::Eight),
        "{}",
        path.display()
    );
    let pixels = bytes[..info.buffer_size()]
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    (info.width, info.height, pixels)
}
