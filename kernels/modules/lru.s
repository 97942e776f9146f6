# lru.s — the 4-way sets of both caches, kept in the order of their last use.
#
# Way 0 is the most recent way and is looked up inline like a direct-mapped line; these
# routines serve the misses there: find the key in ways 1..3, and rotate a set so that
# one way moves to the front (a hit in another way), or the least recent way is evicted
# for a new line (rotate way 3 to the front, then overwrite it). The caller passes the
# addresses of way 0's tag and line and the strides from one way to the next.
#
# lru_find: the way (1..3) of the set whose tag is $116 to $100, 0 if none; tags at
# $101 + w * $103. Returns to $0.
#
# Registers of lru_find (tests/src/lib.rs's module harness checks them):
#   in:       $0 $101 $103 $116
#   out:      $100
#   clobbers: $105 $107..$109
#
# Registers of lru_rotate (below):
#   in:       $0 $100..$104
#   out:      -
#   clobbers: $100 $105..$115

        .text
lru_find:
        il      $100, 0
        ori     $105, $101, 0
        il      $107, 1
1:      a       $105, $105, $103
        lqd     $108, 0($105)
        ceq     $109, $108, $116
        brnz    $109, 2f
        ai      $107, $107, 1
        ceqi    $109, $107, 4
        brz     $109, 1b
        bi      $0
2:      ori     $100, $107, 0
        bi      $0

# lru_rotate: way $100 (1..3) becomes way 0 and ways 0 .. $100-1 move down one: the
# ways stay in the order of their last use. Tags at $101 + w * $103, 64-byte lines at
# $102 + w * $104. Uses $100, $105..$115.
lru_rotate:
        ori     $105, $101, 0
        ori     $106, $102, 0
        ori     $107, $100, 0
1:      a       $105, $105, $103
        a       $106, $106, $104
        ai      $107, $107, -1
        brnz    $107, 1b
        lqd     $108, 0($105)
        lqd     $109, 0($106)
        lqd     $110, 16($106)
        lqd     $111, 32($106)
        lqd     $112, 48($106)
2:      sf      $113, $103, $105
        sf      $114, $104, $106
        lqd     $115, 0($113)
        stqd    $115, 0($105)
        lqd     $115, 0($114)
        stqd    $115, 0($106)
        lqd     $115, 16($114)
        stqd    $115, 16($106)
        lqd     $115, 32($114)
        stqd    $115, 32($106)
        lqd     $115, 48($114)
        stqd    $115, 48($106)
        ori     $105, $113, 0
        ori     $106, $114, 0
        ai      $100, $100, -1
        brnz    $100, 2b
        stqd    $108, 0($101)
        stqd    $109, 0($102)
        stqd    $110, 16($102)
        stqd    $111, 32($102)
        stqd    $112, 48($102)
        bi      $0

