//! Events, the decrementer, SRR0/`iret`, `bisled`, the interrupt-enable bit and SPU
//! interrupts on the simulated SPU (`spu_isa::machine`). Event bit values are those of the
//! SDK's `spu_mfcio.h`: tag group 0x1, list stall 0x2, inbound mailbox 0x10, decrementer
//! 0x20, outbound interrupt mailbox available 0x40, outbound mailbox available 0x80,
//! signal 2 0x100, signal 1 0x200, reservation lost 0x400.

use spu_isa::machine::{event, MainMemory, Spu, StopReason};

/// Assembles `src` (a whole program with `_start`) into a fresh SPU.
fn load(src: &str) -> Spu {
    let src = format!("        .text\n{src}\n");
    let out = spu_asm::assemble(&src, "t.s", &Default::default())
        .unwrap_or_else(|d| panic!("{d:?}\n{src}"));
    let mut spu = Spu::new(0);
    spu.load_image(&out.image);
    spu.set_pc(out.entry);
    spu
}

fn run(spu: &mut Spu) -> StopReason {
    let mut mem = MainMemory::zeroed(64 * 1024);
    spu.run(&mut mem, 1_000_000)
}

#[test]
fn event_bits_have_the_sdk_values() {
    assert_eq!(event::TAG_GROUP, 0x1);
    assert_eq!(event::LIST_STALL, 0x2);
    assert_eq!(event::IN_MBOX, 0x10);
    assert_eq!(event::DECREMENTER, 0x20);
    assert_eq!(event::OUT_INTR_MBOX, 0x40);
    assert_eq!(event::OUT_MBOX, 0x80);
    assert_eq!(event::SIGNAL2, 0x100);
    assert_eq!(event::SIGNAL1, 0x200);
    assert_eq!(event::LR, 0x400);
}

#[test]
fn iret_returns_to_what_spu_wrsrr0_wrote() {
    let mut spu = load(
        "_start: ila $3, there
        wrch $SPU_WrSRR0, $3
        rdch $4, $SPU_RdSRR0
        iret
        stop 1
there:  stop 2",
    );
    assert_eq!(run(&mut spu), StopReason::Stop(2));
    assert_eq!(spu.reg(4), [20, 0, 0, 0]);
    assert_eq!(spu.srr0(), 20);
}

#[test]
fn e_and_d_forms_set_and_clear_the_interrupt_enable_bit() {
    // RdMachStat bit 0 is the interrupt-enable bit; no event is enabled, so nothing
    // interrupts.
    let mut spu = load(
        "_start: ila $3, on
        bie $3
on:     rdch $4, $SPU_RdMachStat
        ila $3, off
        bid $3
off:    rdch $5, $SPU_RdMachStat
        stop 1",
    );
    assert_eq!(run(&mut spu), StopReason::Stop(1));
    assert_eq!(spu.reg(4)[0], 1);
    assert_eq!(spu.reg(5)[0], 0);
    assert!(!spu.interrupts_enabled());
}

#[test]
fn decrementer_counts_down_and_raises_its_event_going_negative() {
    // Write 100, enable the decrementer event, wait on SPU_RdEventStat: with timing off a
    // cycle is an instruction, so the event comes 101 cycles after the write.
    let mut spu = load(
        "_start: il $3, 100
        wrch $SPU_WrDec, $3
        rdch $9, $SPU_RdDec
        il $4, 0x20
        wrch $SPU_WrEventMask, $4
        rdch $5, $SPU_RdEventStat
        rdch $6, $SPU_RdDec
        wrch $SPU_WrEventAck, $5
        rchcnt $7, $SPU_RdEventStat
        rdch $8, $SPU_RdEventMask
        stop 1",
    );
    assert_eq!(run(&mut spu), StopReason::Stop(1));
    // One cycle after the write (the rdch issues the next cycle).
    assert_eq!(spu.reg(9)[0], 99);
    assert_eq!(spu.reg(5)[0], 0x20);
    // The event arrives at write + 101 (count -1); the next read issues a cycle later.
    assert_eq!(spu.reg(6)[0], 0xffff_fffe);
    assert_eq!(spu.reg(7)[0], 0, "acknowledged");
    assert_eq!(spu.reg(8)[0], 0x20);
    assert!(spu.cycles() >= 101);
}

#[test]
fn decrementer_follows_the_configured_timebase() {
    let mut spu = load(
        "_start: il $3, 5
        wrch $SPU_WrDec, $3
        il $4, 0x20
        wrch $SPU_WrEventMask, $4
        rdch $5, $SPU_RdEventStat
        stop 1",
    );
    spu.decrementer_cycles_per_tick = 10;
    assert_eq!(run(&mut spu), StopReason::Stop(1));
    assert_eq!(spu.reg(5)[0], 0x20);
    // Written at cycle 1; six ticks of ten cycles later it goes from 0 to -1.
    assert_eq!(spu.cycles(), 1 + 60 + 2);
}

#[test]
fn mailbox_and_signal_events() {
    let mut spu = load(
        "_start: il $4, 0x310
        wrch $SPU_WrEventMask, $4
        rdch $5, $SPU_RdEventStat
        stop 1",
    );
    spu.write_inbound_mailbox(7);
    spu.write_signal(0, 1);
    assert_eq!(run(&mut spu), StopReason::Stop(1));
    assert_eq!(spu.reg(5)[0], event::IN_MBOX | event::SIGNAL1);

    // The outbound mailbox's event: the host read it.
    let mut spu = load(
        "_start: il $3, 9
        wrch $SPU_WrOutMbox, $3
        il $4, 0x80
        wrch $SPU_WrEventMask, $4
        rchcnt $5, $SPU_RdEventStat
        stop 1
        rdch $6, $SPU_RdEventStat
        stop 2",
    );
    assert_eq!(run(&mut spu), StopReason::Stop(1));
    assert_eq!(spu.reg(5)[0], 0);
    assert_eq!(spu.read_outbound_mailbox(), Some(9));
    assert_eq!(run(&mut spu), StopReason::Stop(2));
    assert_eq!(spu.reg(6)[0], event::OUT_MBOX);
}

#[test]
fn tag_group_event_waits_for_the_update_request() {
    // A get of 128 bytes; the tag-group event (mask 0x1) arrives once the "all" request
    // for tag 5 is satisfied, i.e. after the DMA completed.
    let mut spu = load(
        "_start: ila $3, 0x4000
        wrch $MFC_LSA, $3
        il $3, 0
        wrch $MFC_EAH, $3
        ila $3, 0x1000
        wrch $MFC_EAL, $3
        il $3, 128
        wrch $MFC_Size, $3
        il $3, 5
        wrch $MFC_TagID, $3
        il $3, 0x40
        wrch $MFC_Cmd, $3
        il $3, 1
        wrch $SPU_WrEventMask, $3
        ila $3, 0x20
        wrch $MFC_WrTagMask, $3
        il $3, 2
        wrch $MFC_WrTagUpdate, $3
        rdch $5, $SPU_RdEventStat
        rdch $6, $MFC_RdTagStat
        stop 1",
    );
    let mut mem = MainMemory::zeroed(64 * 1024);
    mem.write_u32(0x1000, 0xabcd_0123);
    assert_eq!(spu.run(&mut mem, 1_000_000), StopReason::Stop(1));
    assert_eq!(spu.reg(5)[0], event::TAG_GROUP);
    assert_eq!(spu.reg(6)[0], 0x20);
    assert_eq!(&spu.ls()[0x4000..0x4004], &[0xab, 0xcd, 0x01, 0x23]);
    // 240 cycles of latency + 16 for 128 bytes at 8 per cycle.
    assert!(spu.cycles() > 256);
}

#[test]
fn bisled_branches_only_with_an_event_pending_and_always_links() {
    let prog = "_start: il $4, 0x10
        wrch $SPU_WrEventMask, $4
        ila $3, taken
        bisled $20, $3
        stop 1
taken:  stop 2";
    let mut spu = load(prog);
    assert_eq!(run(&mut spu), StopReason::Stop(1));
    assert_eq!(spu.reg(20), [16, 0, 0, 0]);

    let mut spu = load(prog);
    spu.write_inbound_mailbox(1);
    assert_eq!(run(&mut spu), StopReason::Stop(2));
    assert_eq!(spu.reg(20), [16, 0, 0, 0]);
}

#[test]
fn an_enabled_event_interrupts_to_zero_with_srr0_and_interrupts_disabled() {
    // The handler at 0 reads SRR0 and the machine status; the main program enables the
    // inbound-mailbox event, then interrupts with `bie`: before the next instruction the
    // SPU takes the interrupt.
    let mut spu = load(
        "handler: rdch $10, $SPU_RdSRR0
        rdch $11, $SPU_RdMachStat
        rdch $12, $SPU_RdInMbox
        iret
        .space 240
_start: il $4, 0x10
        wrch $SPU_WrEventMask, $4
        ila $3, next
        bie $3
next:   il $13, 1
        stop 4",
    );
    spu.write_inbound_mailbox(0x55);
    assert_eq!(run(&mut spu), StopReason::Stop(4));
    assert_eq!(
        spu.reg(10)[0],
        0x100 + 16,
        "SRR0 = the interrupted instruction"
    );
    assert_eq!(spu.reg(11)[0], 0, "interrupts disabled in the handler");
    assert_eq!(spu.reg(12)[0], 0x55);
    assert_eq!(
        spu.reg(13)[0],
        1,
        "iret resumed at the interrupted instruction"
    );
    assert!(
        !spu.interrupts_enabled(),
        "iret (no E bit) leaves interrupts disabled"
    );
}
