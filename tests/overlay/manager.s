# A small SPU overlay manager for `spu ld`'s overlay stubs (docs/linker.md): a stub
# branches here with the overlay's number in $78 and the target in $79; this loads the
# overlay from the program's image in main memory (at the address the loader leaves in
# `_EAR_`, as libspe2 does, plus the overlay's file offset from `_ovly_table`) with one
# DMA and goes on to the target, $0 still the caller's return address.  It always
# loads (no residency check), and a call from one overlay into another of the same
# region would not return (there is no `__ovly_return` bookkeeping): the overlays are
# called from the non-overlay code only.  Uses $75-$79, which the stubs own.

        .text
        .global __ovly_load
        .type   __ovly_load, @function
__ovly_load:
        shli    $75, $78, 4             # the entry: {vma, size, file offset, buffer}
        ila     $76, _ovly_table-16
        lqx     $77, $76, $75
        ila     $76, _EAR_
        lqd     $76, 0($76)             # {EA high, EA low} of the image
        rotqbyi $78, $77, 8
        rotqbyi $75, $76, 4
        a       $78, $75, $78           # EA low + file offset
        wrch    $MFC_LSA, $77
        wrch    $MFC_EAH, $76
        wrch    $MFC_EAL, $78
        rotqbyi $75, $77, 4
        wrch    $MFC_Size, $75
        il      $75, 31
        wrch    $MFC_TagID, $75
        il      $75, 0x40               # GET
        wrch    $MFC_Cmd, $75
        ilhu    $75, 0x8000             # tag 31
        wrch    $MFC_WrTagMask, $75
        il      $75, 2                  # all
        wrch    $MFC_WrTagUpdate, $75
        rdch    $75, $MFC_RdTagStat
        sync
        bi      $79
        .size   __ovly_load, .-__ovly_load

        .global __ovly_return
        .type   __ovly_return, @function
__ovly_return:
        bi      $0
        .size   __ovly_return, .-__ovly_return
