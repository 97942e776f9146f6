# An overlay program for `spu ld -T overlay.ld` (tests/tests/overlay_program.rs): two
# functions in two overlays of one region, called one, two, one from the non-overlay
# code, each printing its own string (puts, a PPE-assisted call) and returning a bit of
# the exit status (1 | 2, then + 1: 4; anything else exits 1).

        .text
        .global _start
        .type   _start, @function
_start:
        il      $80, 0
        brsl    $0, one
        or      $80, $80, $3
        brsl    $0, two
        or      $80, $80, $3
        brsl    $0, one
        a       $80, $80, $3
        ceqi    $81, $80, 4
        brnz    $81, .Lgood
        stop    0x2001
.Lgood: stop    0x2004
        .size   _start, .-_start

        .section .ov_one, "ax", @progbits
        .global one
        .type   one, @function
one:
        ila     $3, .Lone
        ila     $4, block
        stqd    $3, 0($4)
        stop    0x2100
        .long   block + (25 << 24)      # puts (C99 opcode 25), its block
        il      $3, 1
        bi      $0
        .size   one, .-one
.Lone:  .string "one: loaded from the image in main memory"

        .section .ov_two, "ax", @progbits
        .global two
        .type   two, @function
two:
        ila     $3, .Ltwo
        ila     $4, block
        stqd    $3, 0($4)
        stop    0x2100
        .long   block + (25 << 24)      # puts (C99 opcode 25), its block
        il      $3, 2
        bi      $0
        .size   two, .-two
.Ltwo:  .string "two: over one, in the same region"

        .section .bss
        .align  4
block:  .space  32
