# fixdfdi.s: double -> 64-bit integer, truncating, which the SPU's double unit has no
# instruction for: libgcc's __fixdfdi and __fixunsdfdi. Outside the range, where C leaves
# the result undefined, they saturate as Rust's `as` does: NaN is 0; __fixdfdi gives
# LLONG_MAX or LLONG_MIN, __fixunsdfdi 0 below zero and ULLONG_MAX from 2^64 up. The
# result is the doubleword in bytes 0..7 of $3 (high word first).

# Splits the double in $3: $5 = the biased exponent e, $6 = all ones when negative,
# $11 = the fraction bits (non-zero words for a NaN when e is 2047), $7 doubleword 0 =
# the truncated magnitude, right for e in 1023..1086. The 53-bit significand m is put in
# the low doubleword of the quadword and shifted left by 12 + (e - 1023) bits: the high
# doubleword is then m * 2^(e - 1075), truncated.
        .macro  PARTS
        rotmai  $6, $3, -31
        fsm     $6, $6                      # all ones when negative
        shli    $5, $3, 1
        rotmi   $5, $5, -21                 # e
        shli    $10, $3, 12
        rotmi   $10, $10, -12               # word 0: the fraction's high 20 bits
        lqr     $12, .Lpair
        shufb   $11, $10, $3, $12           # {fraction high, low word, 0, 0}
        ilhu    $8, 0x0010
        or      $10, $10, $8                # the implicit one
        shufb   $7, $10, $3, $12            # m, in doubleword 0
        rotqbyi $7, $7, 8                   # m, in doubleword 1
        il      $8, -1011
        a       $8, $5, $8                  # 12 + e - 1023
        shlqbybi $7, $7, $8
        shlqbi  $7, $7, $8
        .endm

        .text
# unsigned long long __fixunsdfdi(double)
        .global __fixunsdfdi
        .type   __fixunsdfdi, @function
__fixunsdfdi:
        PARTS
        brnz    $6, .Lzero                  # negative (and -NaN): 0
        il      $8, 1022
        cgt     $9, $5, $8
        brz     $9, .Lzero                  # below 1
        il      $8, 1086
        cgt     $9, $5, $8
        brnz    $9, .Lubig                  # 2^64 and up, inf, NaN
        ori     $3, $7, 0
        bi      $0
.Lubig:
        il      $8, 2047
        ceq     $9, $5, $8
        brz     $9, .Lumax
        orx     $10, $11
        brnz    $10, .Lzero                 # NaN
.Lumax:
        il      $3, -1
        bi      $0
.Lzero:
        il      $3, 0
        bi      $0
        .size   __fixunsdfdi, .-__fixunsdfdi

# long long __fixdfdi(double)
        .global __fixdfdi
        .type   __fixdfdi, @function
__fixdfdi:
        PARTS
        il      $8, 1022
        cgt     $9, $5, $8
        brz     $9, .Lzero                  # below 1 in magnitude
        il      $8, 1085
        cgt     $9, $5, $8
        brnz    $9, .Lsbig                  # 2^63 and up in magnitude, inf, NaN
        ori     $3, $7, 0
        brz     $6, .Lpos
        ceqi    $12, $3, 0
        rotqbyi $12, $12, 4                 # word 0: all ones when the low word is 0
        nor     $13, $3, $3
        sf      $13, $12, $13               # word 0: -x's high word, ~hi + (lo == 0)
        sfi     $14, $3, 0                  # word 1: -x's low word
        fsmbi   $15, 0xf000
        selb    $3, $14, $13, $15
.Lpos:
        bi      $0
.Lsbig:
        il      $8, 2047
        ceq     $9, $5, $8
        brz     $9, .Lsat
        orx     $10, $11
        brnz    $10, .Lzero                 # NaN
.Lsat:
        ilhu    $3, 0x8000
        fsmbi   $8, 0xf000
        and     $3, $3, $8                  # LLONG_MIN
        brnz    $6, .Lpos
        il      $8, -1
        xor     $3, $3, $8                  # LLONG_MAX
        bi      $0
        .size   __fixdfdi, .-__fixdfdi

        .section .rodata
        .align  4
.Lpair:                                     # shufb: word 0 of the first, word 1 of the second
        .long   0x00010203, 0x14151617, 0x80808080, 0x80808080
