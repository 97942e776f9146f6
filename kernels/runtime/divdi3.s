# divdi3.s: libgcc's 64-bit integer division, which spu-gcc calls for `long long` / and %
# (__divdi3, __udivdi3, __moddi3, __umoddi3), and the unsigned core the 32-bit helpers
# share. A 64-bit value is the doubleword in bytes 0..7 of its register (the preferred
# slot). Division is restoring shift-and-subtract, one quotient bit a step: exact for every
# operand; by zero it gives the quotient all ones and the remainder the dividend, as the
# subtraction then always succeeds (C leaves it undefined; this is what the SPU computes).

        .text
# __udivmod64: $3 = n, $4 = d (doublewords) -> $3 = n / d, $4 = n % d. Uses $5..$12 only.
# The dividend rides in words 2,3 of one quadword under the partial remainder in words
# 0,1, so one 128-bit shift moves its top bit into the remainder.
        .global __udivmod64
        .type   __udivmod64, @function
__udivmod64:
        lqr     $5, .Lhigh_dw               # {-1, -1, 0, 0}
        and     $4, $4, $5                  # d with words 2,3 clear
        rotqmbyi $6, $3, -8                 # {0, 0, n}: remainder 0, dividend n
        lqr     $11, .Lsplat0
        lqr     $12, .Lbit0                 # {0, 0, 0, 1}
        il      $10, 64
1:      shlqbii $6, $6, 1
        bg      $7, $4, $6                  # per word: 1 when no borrow
        shlqbyi $7, $7, 4                   # the low word's into word 0 (word 1 gets 1)
        ori     $8, $7, 0
        sfx     $8, $4, $6                  # remainder - d (64-bit)
        bgx     $7, $4, $6                  # word 0: 1 when remainder >= d
        ceqi    $7, $7, 1
        shufb   $7, $7, $7, $11             # all ones everywhere when it fits
        and     $9, $7, $5
        selb    $6, $6, $8, $9              # take the difference
        and     $9, $7, $12
        or      $6, $6, $9                  # and a quotient bit
        ai      $10, $10, -1
        brnz    $10, 1b
        and     $4, $6, $5                  # remainder
        shlqbyi $3, $6, 8                   # quotient
        bi      $0
        .size   __udivmod64, .-__udivmod64

# __neg64_if: $3 = x, $5 = mask (all ones: negate) -> $3 = mask ? -x : x. Uses $6..$8.
        .global __neg64_if
        .type   __neg64_if, @function
__neg64_if:
        lqr     $8, .Lhigh_dw
        and     $3, $3, $8
        il      $6, 0
        bg      $7, $3, $6
        shlqbyi $7, $7, 4
        sfx     $7, $3, $6                  # 0 - x
        selb    $3, $3, $7, $5
        bi      $0
        .size   __neg64_if, .-__neg64_if

# The sign of $3's doubleword as a mask of all ones (negative) or zeros, into REG.
        .macro  SIGN reg, src
        rotmai  \reg, \src, -31
        shufb   \reg, \reg, \reg, $15
        .endm

# unsigned long long __udivdi3(unsigned long long, unsigned long long)
        .global __udivdi3
        .type   __udivdi3, @function
__udivdi3:
        stqd    $0, 16($1)
        stqd    $1, -32($1)
        ai      $1, $1, -32
        brsl    $0, __udivmod64
        ai      $1, $1, 32
        lqd     $0, 16($1)
        bi      $0
        .size   __udivdi3, .-__udivdi3

# unsigned long long __umoddi3(unsigned long long, unsigned long long)
        .global __umoddi3
        .type   __umoddi3, @function
__umoddi3:
        stqd    $0, 16($1)
        stqd    $1, -32($1)
        ai      $1, $1, -32
        brsl    $0, __udivmod64
        ori     $3, $4, 0
        ai      $1, $1, 32
        lqd     $0, 16($1)
        bi      $0
        .size   __umoddi3, .-__umoddi3

# long long __divdi3(long long, long long): the magnitudes divided, the quotient negated
# when the signs differ (LLONG_MIN / -1 wraps to LLONG_MIN).
        .global __divdi3
        .type   __divdi3, @function
__divdi3:
        stqd    $0, 16($1)
        stqd    $1, -32($1)
        ai      $1, $1, -32
        lqr     $15, .Lsplat0
        SIGN    $13, $3
        SIGN    $14, $4
        xor     $16, $13, $14               # the quotient's sign
        ori     $5, $13, 0
        brsl    $0, __neg64_if              # |n|
        ori     $17, $3, 0
        ori     $3, $4, 0
        ori     $5, $14, 0
        brsl    $0, __neg64_if              # |d|
        ori     $4, $3, 0
        ori     $3, $17, 0
        brsl    $0, __udivmod64
        ori     $5, $16, 0
        brsl    $0, __neg64_if
        ai      $1, $1, 32
        lqd     $0, 16($1)
        bi      $0
        .size   __divdi3, .-__divdi3

# long long __moddi3(long long, long long): the remainder takes the dividend's sign.
        .global __moddi3
        .type   __moddi3, @function
__moddi3:
        stqd    $0, 16($1)
        stqd    $1, -32($1)
        ai      $1, $1, -32
        lqr     $15, .Lsplat0
        SIGN    $13, $3
        SIGN    $14, $4
        ori     $5, $13, 0
        brsl    $0, __neg64_if
        ori     $17, $3, 0
        ori     $3, $4, 0
        ori     $5, $14, 0
        brsl    $0, __neg64_if
        ori     $4, $3, 0
        ori     $3, $17, 0
        brsl    $0, __udivmod64
        ori     $3, $4, 0
        ori     $5, $13, 0
        brsl    $0, __neg64_if
        ai      $1, $1, 32
        lqd     $0, 16($1)
        bi      $0
        .size   __moddi3, .-__moddi3

        .section .rodata
        .align  4
.Lhigh_dw:
        .long   -1, -1, 0, 0
.Lsplat0:
        .long   0x00010203, 0x00010203, 0x00010203, 0x00010203
.Lbit0:
        .long   0, 0, 0, 1
