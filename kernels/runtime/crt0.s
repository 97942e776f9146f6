# crt0.s: the program's entry, as spu-gcc's startup (newlib's crt0 built for a C99
# `main`) did it. `spu as --runtime` links it first; docs/running-programs.md.
#
# From a shell, elfspe passes $3 = argc and $4 = {LS address, EA high, EA low, size} of
# the argv region: it is copied from main memory to the top of local store (the loader
# put it there already; the copy is what crt0 did on the Cell, and changes nothing). Through
# the libspe2 API, $3, $4, $5 are speid, argp, envp and $4's size word is 0: nothing to
# copy. Either way main gets $3, $4, $5 as they came, and its return value goes to exit.

        .text
        .global _start
        .type   _start, @function
_start:
        rotqbyi $7, $4, 12              # the argv region's size
        brz     $7, .Lno_args
        wrch    $MFC_LSA, $4
        rotqbyi $8, $4, 4
        wrch    $MFC_EAH, $8
        rotqbyi $8, $4, 8
        wrch    $MFC_EAL, $8
        wrch    $MFC_Size, $7
        il      $8, 0
        wrch    $MFC_TagID, $8
        il      $8, 0x40                # get
        wrch    $MFC_Cmd, $8
        il      $8, 1
        wrch    $MFC_WrTagMask, $8
        il      $8, 2                   # wait for all
        wrch    $MFC_WrTagUpdate, $8
        rdch    $8, $MFC_RdTagStat
.Lno_args:
        # $1 is the loader's: below the arguments, with the available stack in word 1.
        il      $0, 0                   # a null link register ends backtraces
        stqd    $0, 0($1)               # and a null back chain ends the stack
        stqd    $1, -32($1)
        ai      $1, $1, -32
        stqd    $0, 16($1)
        brsl    $0, main
        brsl    $0, exit
        .size   _start, .-_start
