# fixdfsi.s: double -> int, truncating, which the SPU's double unit has no instruction
# for: libgcc's __fixdfsi and __fixunsdfsi, with libgcc's results outside the range: NaN
# is 0; __fixdfsi saturates to INT_MAX or INT_MIN; __fixunsdfsi is libgcc2's: from 2^31
# up it converts x - 2^31 and adds 2^31 back (so 2^32 and up, and +inf, give 0xffffffff),
# below that it is __fixdfsi's result as unsigned (-1.5 gives 0xffffffff).

# Splits the double in $3 (high word, low word): $4 = the biased exponent, $5 = all ones
# when negative, $6 = the truncated magnitude (right for exponents 1023..1054), $7 = non-zero
# for a NaN. Uses $8..$21.
        .macro  PARTS
        rotqbyi $8, $3, 4                   # low word
        rotmai  $5, $3, -31
        rotmi   $4, $3, -20
        il      $9, 0x7ff
        and     $4, $4, $9
        ilhu    $10, 0x000f
        iohl    $10, 0xffff
        and     $11, $3, $10
        ilhu    $12, 0x0010
        or      $12, $11, $12               # the significand's high 21 bits
        il      $13, 1075
        sf      $13, $4, $13                # s = 1075 - exponent: the right shift
        sfi     $14, $13, 0
        rotm    $15, $8, $14                # low >> s
        sfi     $16, $13, 32
        shl     $17, $12, $16               # high << (32 - s), 0 past 32
        rotm    $18, $12, $16               # high >> (s - 32), 0 below 32
        or      $6, $15, $17
        or      $6, $6, $18
        or      $19, $11, $8                # a NaN: exponent all ones, fraction not 0
        ceq     $20, $4, $9
        ceqi    $21, $19, 0
        andc    $7, $20, $21
        .endm

        .text
# int __fixdfsi(double)
        .global __fixdfsi
        .type   __fixdfsi, @function
__fixdfsi:
        PARTS
        brnz    $7, 1f
        il      $9, 1023
        cgt     $9, $9, $4
        brnz    $9, 1f                      # |x| < 1
        il      $9, 1054
        cgt     $9, $9, $4
        brz     $9, 2f                      # |x| >= 2^31
        xor     $3, $6, $5
        sf      $3, $5, $3
        bi      $0
1:      il      $3, 0
        bi      $0
2:      ilhu    $3, 0x7fff
        iohl    $3, 0xffff
        xor     $3, $3, $5
        bi      $0
        .size   __fixdfsi, .-__fixdfsi

# unsigned __fixunsdfsi(double)
        .global __fixunsdfsi
        .type   __fixunsdfsi, @function
__fixunsdfsi:
        PARTS
        brnz    $7, 1f
        il      $9, 1023
        cgt     $9, $9, $4
        brnz    $9, 1f                      # |x| < 1
        brnz    $5, 3f
        il      $9, 1055
        cgt     $9, $9, $4
        brz     $9, 2f                      # x >= 2^32
        ori     $3, $6, 0
        bi      $0
1:      il      $3, 0
        bi      $0
2:      il      $3, -1
        bi      $0
3:      il      $9, 1054                    # negative: __fixdfsi's result
        cgt     $9, $9, $4
        brz     $9, 4f
        sfi     $3, $6, 0
        bi      $0
4:      ilhu    $3, 0x8000
        bi      $0
        .size   __fixunsdfsi, .-__fixunsdfsi
