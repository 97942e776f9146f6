# floatsidf.s: int -> double, which the SPU's double unit has no instruction for: libgcc's
# __floatsidf and __floatunsidf, and __float_unssidf, the name spu-gcc's unsigned
# conversion calls. Every 32-bit integer is exact as a double: the leading one found with
# clz sets the exponent, the bits after it are the fraction. A double is the doubleword in
# bytes 0..7 of $3.

        .text
# $3 word 0 = the magnitude u, $10 word 0 = the sign bit to set -> $3 = (double) u, signed.
__df_of_magnitude:
        clz     $4, $3                      # n leading zeros (32 for 0)
        shl     $5, $3, $4                  # the leading one to bit 31
        a       $5, $5, $5                  # and dropped: the fraction's top 32 bits
        il      $6, 1054                    # 1023 + 31
        sf      $6, $4, $6                  # the exponent: 1054 - n
        ceqi    $7, $4, 32
        andc    $6, $6, $7                  # 0 for 0
        shli    $6, $6, 20
        rotmi   $8, $5, -12
        or      $6, $6, $8                  # high word: exponent, fraction's top 20 bits
        or      $6, $6, $10
        shli    $9, $5, 20                  # low word: the fraction's next 12 bits
        lqr     $7, .Lpair
        shufb   $3, $6, $9, $7              # {high, low, 0, 0}
        bi      $0
        .size   __df_of_magnitude, .-__df_of_magnitude

# double __floatunsidf(unsigned), __float_unssidf(unsigned)
        .global __floatunsidf
        .type   __floatunsidf, @function
        .global __float_unssidf
        .type   __float_unssidf, @function
__floatunsidf:
__float_unssidf:
        il      $10, 0
        br      __df_of_magnitude
        .size   __floatunsidf, .-__floatunsidf

# double __floatsidf(int): the magnitude (INT_MIN's is 2^31, as unsigned) and the sign.
        .global __floatsidf
        .type   __floatsidf, @function
__floatsidf:
        rotmai  $4, $3, -31                 # all ones when negative
        xor     $3, $3, $4
        sf      $3, $4, $3                  # |i|
        ilhu    $10, 0x8000
        and     $10, $10, $4
        br      __df_of_magnitude
        .size   __floatsidf, .-__floatsidf

        .section .rodata
        .align  4
.Lpair:                                     # shufb: word 0 of each operand, then zeros
        .long   0x00010203, 0x10111213, 0x80808080, 0x80808080
