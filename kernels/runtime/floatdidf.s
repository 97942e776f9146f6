# floatdidf.s: 64-bit integer -> double, which the SPU's double unit has no instruction
# for: libgcc's __floatdidf and __floatundidf, and __float_unsdidf, the name spu-gcc's
# unsigned conversion calls. Each 32-bit half of the magnitude is exact as a double (the
# leading one found with clz sets the exponent, the high half's 32 higher), and one `dfa`
# adds the two: the sum is rounded once, to nearest even, as C's conversion rounds. A
# `long long` is the doubleword in bytes 0..7 of $3 (high word first); so is the double.

        .text
# $3 doubleword 0 = the magnitude u, $10 word 0 = the sign bit to set -> $3 = (double) u,
# signed.
__df_of_u64:
        clz     $4, $3                      # n leading zeros of each half (32 for 0)
        shl     $5, $3, $4                  # the leading one to bit 31
        a       $5, $5, $5                  # and dropped: the fraction's top 32 bits
        lqr     $6, .Lbias
        sf      $6, $4, $6                  # the exponents: {1086 - n, 1054 - n}
        ceqi    $7, $4, 32
        andc    $6, $6, $7                  # 0 for a zero half
        shli    $6, $6, 20
        rotmi   $8, $5, -12
        or      $6, $6, $8                  # high words: exponent, fraction's top 20 bits
        shli    $9, $5, 20                  # low words: the fraction's next 12 bits
        lqr     $7, .Lhigh
        shufb   $11, $6, $9, $7             # the high half times 2^32, exact
        lqr     $7, .Llow
        shufb   $12, $6, $9, $7             # the low half, exact
        dfa     $3, $11, $12                # rounded once
        or      $3, $3, $10
        bi      $0
        .size   __df_of_u64, .-__df_of_u64

# double __floatundidf(unsigned long long), __float_unsdidf(unsigned long long)
        .global __floatundidf
        .type   __floatundidf, @function
        .global __float_unsdidf
        .type   __float_unsdidf, @function
__floatundidf:
__float_unsdidf:
        il      $10, 0
        br      __df_of_u64
        .size   __floatundidf, .-__floatundidf

# double __floatdidf(long long): the magnitude (LLONG_MIN's is 2^63, as unsigned) and the
# sign.
        .global __floatdidf
        .type   __floatdidf, @function
__floatdidf:
        rotmai  $4, $3, -31
        fsm     $4, $4                      # all ones when negative
        ceqi    $5, $3, 0
        rotqbyi $5, $5, 4                   # word 0: all ones when the low word is 0
        nor     $6, $3, $3
        sf      $6, $5, $6                  # word 0: -x's high word, ~hi + (lo == 0)
        sfi     $7, $3, 0                   # word 1: -x's low word
        fsmbi   $8, 0xf000
        selb    $7, $7, $6, $8              # -x
        selb    $3, $3, $7, $4              # |x|
        ilhu    $10, 0x8000
        and     $10, $10, $4
        and     $10, $10, $8                # the sign bit, in word 0 only
        br      __df_of_u64
        .size   __floatdidf, .-__floatdidf

        .section .rodata
        .align  4
.Lbias:                                     # 1023 + 31, and 32 more for the high half
        .long   1086, 1054, 0, 0
.Lhigh:                                     # shufb: word 0 of each operand, then zeros
        .long   0x00010203, 0x10111213, 0x80808080, 0x80808080
.Llow:                                      # shufb: word 1 of each operand, then zeros
        .long   0x04050607, 0x14151617, 0x80808080, 0x80808080
