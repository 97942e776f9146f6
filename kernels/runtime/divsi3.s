# divsi3.s: libgcc's 32-bit integer division entry points (__divsi3, __udivsi3,
# __modsi3, __umodsi3), for code that calls them rather than dividing inline. Each widens
# its operands to 64 bits and uses the 64-bit helpers of divdi3.s, so the two agree on
# every operand: INT_MIN / -1 wraps to INT_MIN, and by zero the quotient is all ones (the
# remainder the dividend) for unsigned operands, as divdi3.s describes.

        .text
# The 32-bit word in REG's preferred slot widened into its doubleword: zero- or (SIGNED)
# sign-extended.
        .macro  WIDEN reg, signed
        rotqmbyi \reg, \reg, -4             # {0, x, y, z}
        .if     \signed
        xswd    \reg, \reg
        .else
        lqr     $9, .Lhigh_dw
        and     \reg, \reg, $9
        .endif
        .endm

# NAME(a, b): HELPER on the widened operands; the low word of its doubleword result.
        .macro  NARROW name, helper, signed
        .global \name
        .type   \name, @function
\name:
        stqd    $0, 16($1)
        stqd    $1, -32($1)
        ai      $1, $1, -32
        WIDEN   $3, \signed
        WIDEN   $4, \signed
        brsl    $0, \helper
        rotqbyi $3, $3, 4
        ai      $1, $1, 32
        lqd     $0, 16($1)
        bi      $0
        .size   \name, .-\name
        .endm

        NARROW  __udivsi3, __udivdi3, 0
        NARROW  __umodsi3, __umoddi3, 0
        NARROW  __divsi3, __divdi3, 1
        NARROW  __modsi3, __moddi3, 1

        .section .rodata
        .align  4
.Lhigh_dw:
        .long   -1, -1, 0, 0
