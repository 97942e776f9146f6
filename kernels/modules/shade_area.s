# shade_area.s — the shading module's local-store area (modules/shade.s), and the macros
# that address it and move data into it.
#
# The area (SH_AREA_BYTES of local store, at the address the host puts in params beside
# the shading block's, above everything the kernel carves) is laid out by
# loader::kernel_abi::ShadingArea, whose offsets are the SH_* of layout.inc: the set-up
# flag, the counters (ShadeCounters: SH_STATS + SHS_*, one per quadword, word 0, read by
# the host from local store as the PPE reads an SPE's memory-mapped local store), the
# shading block, the lights' splats, the i-set, the colour blocks, the visibility masks,
# the vertex and material caches and the vertices in flight. It is set up on the first
# call (modules/shade_cache.s). Below: what the code assumes of that layout, and the
# arrays that share room once the i-set is built. No code: definitions only.

        .set SH_IRR_R, SH_SCRATCH       # irradiance r, g, b of the i-set (after the i-set
        .set SH_IRR_G, SH_STAGE         # is built, over its scratch: 16 vectors each)
        .set SH_IRR_B, SH_NRM
        .if     SH_NRM != SH_STAGE + 256
        .error  "the slow path reads the records and normals from one base"
        .endif
        .if     SH_IRR_G != SH_IRR_R + 256 || SH_IRR_B != SH_IRR_R + 512
        .error  "the irradiance sums are read from one base"
        .endif
        .if     SH_DEFER + SH_IN_FLIGHT * 32 > SH_VSTAGE || SH_VSTAGE + SH_IN_FLIGHT * 64 != SH_AREA_BYTES
        .error  "the vertices in flight do not fit"
        .endif
        .set SH_TAG, 5                  # fetches; colour output on 6 and 7

# rt = ra + an area offset (beyond ai's 10 bits, up to 18; $96 is the scratch)
        .macro  SH_ADDI rt, ra, off
        ila     $96, \off
        a       \rt, \ra, $96
        .endm

# wait for the fetches on tag SH_TAG (tmp: a scratch register)
        .macro  SH_WAIT tmp
        il      \tmp, 1 << SH_TAG
        wrch    $MFC_WrTagMask, \tmp
        il      \tmp, 2
        wrch    $MFC_WrTagUpdate, \tmp
        rdch    \tmp, $MFC_RdTagStat
        .endm

# queue a get LS <- EA of SIZE bytes (an immediate) on tag SH_TAG, not waited for
# (registers: ls, ea, scratch; the scratch may be ea)
        .macro  SH_QUEUE ls, ea, size, tmp
        wrch    $MFC_LSA, \ls
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, \ea
        il      \tmp, \size
        wrch    $MFC_Size, \tmp
        il      \tmp, SH_TAG
        wrch    $MFC_TagID, \tmp
        il      \tmp, 0x40
        wrch    $MFC_Cmd, \tmp
        .endm

# get LS <- EA, SIZE bytes on tag SH_TAG and wait (registers: ls, ea, size, scratch)
        .macro  SH_GET ls, ea, size, tmp
        wrch    $MFC_LSA, \ls
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, \ea
        wrch    $MFC_Size, \size
        il      \tmp, SH_TAG
        wrch    $MFC_TagID, \tmp
        il      \tmp, 0x40
        wrch    $MFC_Cmd, \tmp
        SH_WAIT \tmp
        .endm

# $71 quadwords of VALUE from the area's OFF on ($72: scratch)
        .macro  SH_FILL value, off
        SH_ADDI $72, $66, \off
1:      stqd    \value, 0($72)
        ai      $72, $72, 16
        ai      $71, $71, -1
        brnz    $71, 1b
        .endm

# counter += 1 (a quadword of SH_STATS; $66 = area)
        .macro  SH_COUNT which, tmp
        lqd     \tmp, SH_STATS+\which($66)
        ai      \tmp, \tmp, 1
        stqd    \tmp, SH_STATS+\which($66)
        .endm
