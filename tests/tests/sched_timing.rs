//! A `.sched` block under the timing model: the docs' example (docs/sched.md) computes the
//! same sums as the block in logical order, in pinned cycle counts, fewer when scheduled.

use spu_asm::{assemble, Options};
use spu_isa::machine::{MainMemory, Spu, StopReason};

const DATA: &str = "
        stop    0x2000
        .data
        .align  4
xs:     .float  1, 2, 3, 4, 5, 6, 7, 8, 1, 2, 3, 4, 5, 6, 7, 8
        .float  1, 2, 3, 4, 5, 6, 7, 8, 1, 2, 3, 4, 5, 6, 7, 8
ys:     .float  1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1
        .float  1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1
";

const START: &str = "
        .text
        .global _start
_start: ila     $3, xs
        ila     $4, ys
        il      $5, 0
        il      $6, 4
";

const LOOP: &str = "
loop:
      ! hbrr    done_br, loop
        lqd     %x0, 0($3)
        lqd     %x1, 16($3)
        lqd     %y0, 0($4)
        lqd     %y1, 16($4)
        fm      %p0, %x0, %y0
        fma     %p1, %x1, %y1, %p0
        ai      $3, $3, 32
        ai      $4, $4, 32
        fa      $5, $5, %p1
        ai      $6, $6, -1
done_br:
        brnz    $6, loop
";

/// Runs a program with the timing model: (cycles, $5).
fn run(source: &str) -> (u64, [u32; 4]) {
    let out = assemble(source, "dot.s", &Options::default()).unwrap_or_else(|d| panic!("{}", d[0]));
    let mut spu = Spu::new(0);
    spu.load_image(&out.image);
    spu.set_pc(out.entry);
    spu.enable_timing(Default::default());
    let stop = spu.run(&mut MainMemory::zeroed(4096), 100_000);
    assert!(matches!(stop, StopReason::Stop(0x2000)), "{stop}");
    (spu.cycles(), spu.reg(5))
}

#[test]
fn the_scheduled_loop_is_faster_and_computes_the_same() {
    let scheduled = format!("{START}        .sched pool=20-31\n{LOOP}        .endsched\n{DATA}");
    // The logical order as written, the virtual registers given fixed numbers.
    let logical = LOOP
        .replace("! ", "")
        .replace("%x0", "$20")
        .replace("%x1", "$21")
        .replace("%y0", "$22")
        .replace("%y1", "$23")
        .replace("%p0", "$24")
        .replace("%p1", "$25");
    let logical = format!("{START}        .align 3\n{logical}{DATA}");
    let sums = [24.0f32, 32.0, 40.0, 48.0].map(f32::to_bits);
    assert_eq!(run(&scheduled), (111, sums));
    assert_eq!(run(&logical), (123, sums));
}
