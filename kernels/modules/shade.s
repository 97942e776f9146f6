# shade.s — shading of a traced 8x8 packet (paper section 7): the i-set, the vertex and
# material caches, multi-pass diffuse shading and the 32-bit colour frame buffer.
#
# `brsl $0, shade_packet` once a packet is traced. In: $68 = local-store address of the
# packet's ray arrays (16 vectors of 4 rays each: dx, dy, dz at +0, +256, +512, t at
# +CTX_RAY_T, the hit triangle's record per ray or -1 at +CTX_RAY_ID), $69 = the packet number
# (tile * 64 + packet), the camera origin and the shading addresses in params. Out: the
# packet's 64 pixels 0xRRGGBBff, row-major, put to ShadingBlock.ea_colour + packet * 256
# (tags 6/7, alternating; the frame's end waits for both). Model: loader/src/shading.rs.
# Keeps $1..$65 (the frame's registers; reads ZERO and EATRIS, and the traversal's
# triangle cache TTAGS, TDATA, TMASK where the kernel has one), uses $66..$127 and $0.
# `brsl $127, shadow_rays` (modules/shadow.s) comes in between: that module's contract
# names what it keeps of $66..$127.
#
# Registers (tests/src/lib.rs's module harness checks them):
#   in:       $0 $68 $69 ZERO EATRIS TTAGS TDATA TMASK
#   out:      -
#   clobbers: $66..$127
#
# The module is four jobs, one file each, composed here behind the one entry; the code
# stays in the order it has always had (the hot loops keep their addresses and fetch
# lines), so a job whose code is in two places is included where each part goes:
#   modules/shade_area.s       the local-store area (its layout is loader::kernel_abi::
#                              ShadingArea, SH_* in layout.inc) and its DMA macros
#   modules/shade_iset.s       1. the i-set: per ray the hit point, normal and material;
#                              its macros and the fast path (same triangle, in the caches)
#   modules/shade_light.s      2. lighting and output: the passes, the material lookup,
#                              the colour block and its put
#   modules/shade_iset_slow.s  1. the i-set's slow path: mixed groups, lane by lane, with
#                              the triangle records' and vertices' DMA staging
#   modules/shade_gather.s     1. with EXT_GATHER, in its place: the slow path batched per
#                              packet, DMA lists and gathers (docs/extensions.md)
#   modules/shade_cache.s      the first call's set-up of the area, and the vertex and
#                              material caches' (and triangle records') misses

        .include "modules/shade_area.s"

        .text
        .align  4
sh_const:
        .long   0x00010203, 0x10111213, 0x04050607, 0x14151617     # +0   transpose: lo pairs
        .long   0x08090a0b, 0x18191a1b, 0x0c0d0e0f, 0x1c1d1e1f     # +16  hi pairs
        .long   0x00010203, 0x04050607, 0x10111213, 0x14151617     # +32  first halves
        .long   0x08090a0b, 0x0c0d0e0f, 0x18191a1b, 0x1c1d1e1f     # +48  second halves
        .long   0x00010203, 0x00010203, 0x00010203, 0x00010203     # +64  splat word 0
        .long   0x04050607, 0x04050607, 0x04050607, 0x04050607     # +80  splat word 1
        .long   0x08090a0b, 0x08090a0b, 0x08090a0b, 0x08090a0b     # +96  splat word 2
        .long   AMBIENT_BITS, AMBIENT_BITS, AMBIENT_BITS, AMBIENT_BITS # +112
        .float  255.0, 255.0, 255.0, 255.0                         # +128
        .float  0.5, 0.5, 0.5, 0.5                                 # +144
        .float  1.5, 1.5, 1.5, 1.5                                 # +160 (unused)
        .float  1.0, 1.0, 1.0, 1.0                                 # +176
        .long   0x000000ff, 0x000000ff, 0x000000ff, 0x000000ff     # +192 a miss: black
        .long   0x0c0d0e0f, 0x0c0d0e0f, 0x0c0d0e0f, 0x0c0d0e0f     # +208 splat word 3
        .long   0x80000000, 0x80000000, 0x80000000, 0x80000000     # +224 sign bits
        .long   1, 1, 1, 0                  # +240 a fast group: groups, same, tri lookups
        .long   0x10111213, 0x00010203, 0x10111213, 0x00010203     # +256 list element (b, a)
        .long   0x001080c0, 0x041480c0, 0x081880c0, 0x0c1c80c0     # +272 r, g top bytes, 0xff
        .long   0x00011003, 0x04051407, 0x0809180b, 0x0c0d1c0f     # +288 b top byte
        .long   0x0004080c, 0x1014181c, 0x80808080, 0x80808080     # +304 top bytes of a, b
        .long   0x80808080, 0x80808080, 0x0004080c, 0x1014181c     # +320 ... to bytes 8-15
        .long   0x00010203, 0x14151617, 0x18191a1b, 0x1c1d1e1f     # +336 a's word 0, b's 1-3
sh_zero:                                      # no irradiance, a black light (768 bytes)
        .space  768

        .align  3
shade_packet:
        .sched  pool=73-89,94-96,98,100-106,110-114,116-118 scratch=66-127
        ila     $70, params
        ila     $90, sh_const
        lqd     $71, PARAM_SHADING_QUAD($70)
        .ifdef  REFLECT                       # the camera's, or 0 for a reflection's
        lqa     $72, rf_origin                # hits (modules/reflect.s)
        .else
        lqd     $72, PARAM_ORIGIN($70)
        .endif
        lqd     $91, 64($90)
        lqd     $92, 80($90)
        lqd     $93, 96($90)
        lqd     $119, 32($90)
        lqd     $120, 208($90)                # splat word 3
        lqd     $122, 224($90)                # sign bits
        ori     $99, $68, 0                   # the rays
        ori     $97, $69, 0                   # the packet number
        rotqbyi $71, $71, PARAM_SHADING_ROT   # shading block EA, area
        rotqbyi $66, $71, 4                   # the shading area
        lqd     $67, SH_FLAG($66)
        lqd     $121, SH_VMASK($66)           # the vertex index mask in every lane
        ilhu    $68, 0x5348
        iohl    $68, 0x4144                   # "SHAD"
        shufb   $107, $72, $72, $91           # origin x, y, z splats
        shufb   $108, $72, $72, $92
        shufb   $109, $72, $72, $93
        ila     %vt, SH_VTAGS
        a       $115, $66, %vt
        ila     %vd, SH_VDATA+16
        a       $123, $66, %vd                # the lines' normals
        il      $124, 0                       # the fast groups' counters (sh_const+240)
        lqd     %id0, CTX_RAY_ID+0($99)
        lqd     %id1, CTX_RAY_ID+16($99)
        lqd     %id2, CTX_RAY_ID+32($99)
        lqd     %id3, CTX_RAY_ID+48($99)
        lqd     %id4, CTX_RAY_ID+64($99)
        lqd     %id5, CTX_RAY_ID+80($99)
        lqd     %id6, CTX_RAY_ID+96($99)
        lqd     %id7, CTX_RAY_ID+112($99)
        lqd     %id8, CTX_RAY_ID+128($99)
        lqd     %id9, CTX_RAY_ID+144($99)
        lqd     %id10, CTX_RAY_ID+160($99)
        lqd     %id11, CTX_RAY_ID+176($99)
        lqd     %id12, CTX_RAY_ID+192($99)
        lqd     %id13, CTX_RAY_ID+208($99)
        lqd     %id14, CTX_RAY_ID+224($99)
        lqd     %id15, CTX_RAY_ID+240($99)
        and     %and1, %id0, %id1
        and     %and2, %id2, %id3
        and     %and3, %id4, %id5
        and     %and4, %id6, %id7
        and     %and5, %id8, %id9
        and     %and6, %id10, %id11
        and     %and7, %id12, %id13
        and     %and8, %id14, %id15
        and     %and9, %and1, %and2
        and     %and10, %and3, %and4
        and     %and11, %and5, %and6
        and     %and12, %and7, %and8
        and     %and13, %and9, %and10
        and     %and14, %and11, %and12
        and     %and15, %and13, %and14
        ceqi    %ne, %and15, -1
        gb      %nb, %ne
        ceqi    $117, %nb, 15                 # no ray of the packet hit
        ceq     $69, $67, $68
        brz     $69, .Lsh_first               # the first call: set up (out of line)
        .endsched
        .include "modules/shade_iset.s"
        .include "modules/shade_light.s"
        .include "modules/shade_iset_slow.s"
        .include "modules/shade_cache.s"
shade_end:
