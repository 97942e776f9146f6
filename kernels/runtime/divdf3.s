# divdf3.s: double division, which the SPU's double unit has no instruction for: libgcc's
# __divdf3, which spu-gcc calls for `/` on doubles. The result is what the double unit
# gives for its own operations (docs/running-programs.md): the quotient rounded to
# nearest, ties to even, with an unbounded exponent; a denormal operand read as a zero of
# its sign; a result below 2^-1022 flushed to a zero of its sign; overflow to infinity;
# any NaN operand, 0/0 and inf/inf give the default NaN 0x7ff8000000000000. The
# significands are divided bit by bit (54 quotient bits: 53 and a guard bit; the
# remainder is the sticky bit), so every quotient is exact before its one rounding.

        .text
# Unpacks the double in SRC: EXP = the biased exponent (word 0), MANT = the 52-bit
# fraction as a doubleword (words 2,3 zero). Uses $20, $21.
        .macro  UNPACK src, exp, mant
        rotmi   \exp, \src, -20
        il      $20, 0x7ff
        and     \exp, \exp, $20
        lqr     $21, .Lfraction
        and     \mant, \src, $21
        .endm

        .global __divdf3
        .type   __divdf3, @function
__divdf3:
        xor     $5, $3, $4
        ilhu    $6, 0x8000
        and     $5, $5, $6                  # $5: the result's sign bit (word 0)
        UNPACK  $3, $7, $8                  # a: $7 exponent, $8 fraction
        UNPACK  $4, $9, $10                 # b: $9, $10
        il      $11, 0x7ff
        rotqbyi $12, $8, 4
        or      $12, $12, $8                # a's fraction not 0 (word 0)
        rotqbyi $13, $10, 4
        or      $13, $13, $10
        ceq     $14, $7, $11                # a: exponent all ones
        ceq     $15, $9, $11
        brz     $14, 1f
        brnz    $12, .Lnan                  # a NaN
1:      brz     $15, 2f
        brnz    $13, .Lnan                  # b NaN
2:      brz     $14, 3f
        brnz    $15, .Lnan                  # inf / inf
        br      .Linf                       # inf / finite
3:      brnz    $15, .Lzero                 # finite / inf
        brnz    $9, 4f
        brz     $7, .Lnan                   # 0 / 0 (denormals are zeros)
        br      .Linf                       # x / 0
4:      brz     $7, .Lzero                  # 0 / y
        # Both normal: significands with the implicit one, the exponent a - b + bias.
        lqr     $16, .Limplicit
        or      $8, $8, $16                 # ma
        or      $10, $10, $16               # mb
        sf      $17, $9, $7
        il      $27, 1023
        a       $17, $17, $27               # $17: the result's biased exponent
        bg      $18, $10, $8                # ma >= mb ?
        shlqbyi $18, $18, 4
        bgx     $18, $10, $8
        brnz    $18, 5f
        shlqbii $8, $8, 1                   # ma < mb: twice ma, one less in the exponent
        ai      $17, $17, -1
5:      # 54 steps of restoring division: $8 words 0,1 the remainder, words 2,3 the
        # quotient; each step subtracts mb when it fits, sets the quotient's low bit, and
        # shifts both left.
        lqr     $16, .Lhigh_dw
        lqr     $19, .Lsplat0
        lqr     $22, .Lbit0
        il      $23, 54
6:      bg      $18, $10, $8
        shlqbyi $18, $18, 4
        ori     $24, $18, 0
        sfx     $24, $10, $8                # remainder - mb
        bgx     $18, $10, $8                # word 0: it fits
        ceqi    $18, $18, 1
        shufb   $18, $18, $18, $19
        and     $25, $18, $16
        selb    $8, $8, $24, $25
        and     $25, $18, $22
        or      $8, $8, $25
        shlqbii $8, $8, 1
        ai      $23, $23, -1
        brnz    $23, 6b
        # The quotient (shifted once more than its 54 bits) and the sticky bit.
        and     $24, $8, $16
        rotqbyi $25, $24, 4
        or      $24, $24, $25               # word 0: the remainder is not 0
        ceqi    $24, $24, 0
        andi    $24, $24, 1
        xori    $24, $24, 1                 # sticky: 1 or 0
        shlqbyi $8, $8, 8
        rotqmbii $8, $8, -1                 # the 54 quotient bits
        and     $8, $8, $16
        rotqbyi $25, $8, 4
        andi    $25, $25, 1                 # the guard bit
        rotqmbii $8, $8, -1                 # the 53-bit significand
        and     $8, $8, $16
        rotqbyi $26, $8, 4
        andi    $26, $26, 1                 # its last bit
        or      $26, $26, $24
        and     $25, $25, $26               # round up: guard and (sticky or odd)
        rotqmbyi $25, $25, -4               # {0, up, ...}
        and     $25, $25, $16
        cg      $26, $8, $25
        shlqbyi $26, $26, 4
        addx    $26, $8, $25                # the significand, rounded
        ilhu    $27, 0x0020
        and     $27, $26, $27
        brz     $27, 7f
        ai      $17, $17, 1                 # rounded up to 2^53: the next binade
7:      il      $27, 2047
        cgt     $28, $27, $17
        brz     $28, .Linf                  # overflow
        cgti    $28, $17, 0
        brz     $28, .Lzero                 # below 2^-1022: flushed
        shli    $17, $17, 20
        ilhu    $27, 0x000f
        iohl    $27, 0xffff
        and     $28, $26, $27
        or      $28, $28, $17
        or      $28, $28, $5                # high word
        rotqbyi $29, $26, 4                 # low word
        br      .Ldone
.Lnan:  ilhu    $28, 0x7ff8
        il      $29, 0
        br      .Ldone
.Linf:  ilhu    $28, 0x7ff0
        or      $28, $28, $5
        il      $29, 0
        br      .Ldone
.Lzero: ori     $28, $5, 0
        il      $29, 0
.Ldone: lqr     $30, .Lpair
        shufb   $3, $28, $29, $30
        bi      $0
        .size   __divdf3, .-__divdf3

        .section .rodata
        .align  4
.Lfraction:
        .long   0x000fffff, -1, 0, 0
.Limplicit:
        .long   0x00100000, 0, 0, 0
.Lhigh_dw:
        .long   -1, -1, 0, 0
.Lsplat0:
        .long   0x00010203, 0x00010203, 0x00010203, 0x00010203
.Lbit0:
        .long   0, 0, 0, 1
.Lpair:                                     # shufb: word 0 of each operand, then zeros
        .long   0x00010203, 0x10111213, 0x80808080, 0x80808080
