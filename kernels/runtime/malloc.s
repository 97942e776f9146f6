# malloc.s: the heap, between the program's end (`_end`, which the linker defines) and
# the stack. sbrk moves the heap's end up as newlib's SPU sbrk did: it refuses to come
# within STACK_RESERVE bytes of the stack pointer, and takes what it gives from the
# available-stack word ($1 word 1, and the same word in every frame of the back chain),
# so the stack's own limit stays true. malloc keeps freed blocks in an address-ordered
# free list (first fit, split when the rest can hold a block, merged with free
# neighbours on free). A block is a 16-byte header {size including the header, next free
# block} before the 16-byte-aligned memory it hands out. Out of memory is 0 with errno
# ENOMEM, as C says.

        .set    STACK_RESERVE, 4096
        .set    ENOMEM, 12

# REG = the word at ADDR (a register holding a 4-aligned address), via TMP.
        .macro  LDW reg, addr
        lqd     \reg, 0(\addr)
        rotqby  \reg, \reg, \addr
        .endm
# The word VAL into ADDR, via T1 and T2.
        .macro  STW val, addr, t1, t2
        lqd     \t1, 0(\addr)
        cwd     \t2, 0(\addr)
        shufb   \t1, \val, \t1, \t2
        stqd    \t1, 0(\addr)
        .endm

        .text
# void *sbrk(intptr_t increment): the old end of the heap, or (void *)-1 with errno
# ENOMEM.
        .global sbrk
        .type   sbrk, @function
sbrk:
        ila     $5, .Lheap_end
        LDW     $6, $5
        brnz    $6, 1f
        ila     $6, _end                    # the first call: the heap starts at _end,
        ai      $6, $6, 15                  # 16-byte aligned
        andi    $6, $6, -16
1:      rotqbyi $7, $1, 4                   # the available stack below $sp ...
        il      $8, STACK_RESERVE
        sf      $7, $8, $7                  # ... less the reserve
        cgt     $8, $3, $7                  # more than that: refused
        brnz    $8, 3f
        a       $7, $6, $3
        STW     $7, $5, $8, $9
        # Take the increment from the available-stack word of $1 and of each frame.
        il      $8, 0
        lqr     $9, .Lword1
        shufb   $8, $3, $8, $9              # {0, increment, 0, 0}
        sf      $1, $8, $1
        ori     $10, $1, 0
2:      lqd     $11, 0($10)                 # the saved {back chain, available, ...}
        sf      $12, $8, $11
        stqd    $12, 0($10)
        ori     $10, $11, 0
        brnz    $10, 2b
        ori     $3, $6, 0
        bi      $0
3:      il      $3, ENOMEM
        ila     $5, errno
        STW     $3, $5, $8, $9
        il      $3, -1
        bi      $0
        .size   sbrk, .-sbrk

# void *malloc(size_t n)
        .global malloc
        .type   malloc, @function
malloc:
        stqd    $0, 16($1)
        stqd    $1, -32($1)
        ai      $1, $1, -32
        ilhu    $5, 4                       # 0x40000: more than local store is refused
        clgt    $6, $3, $5
        brnz    $6, .Lmalloc_enomem
        ai      $3, $3, 31                  # + header, rounded up to 16
        andi    $3, $3, -16
        ila     $5, .Lfree_list             # $5: the link to the block looked at
        LDW     $6, $5                      # $6: that block
1:      brz     $6, .Lmalloc_grow
        LDW     $7, $6                      # its size
        clgt    $8, $3, $7
        brnz    $8, 2f
        ai      $9, $6, 4
        LDW     $10, $9                     # its next
        sf      $11, $3, $7                 # what would be left
        clgti   $8, $11, 31
        brz     $8, 3f
        a       $12, $6, $3                 # split: the rest is a free block
        STW     $11, $12, $13, $14
        ai      $15, $12, 4
        STW     $10, $15, $13, $14
        STW     $3, $6, $13, $14
        ori     $10, $12, 0
3:      STW     $10, $5, $13, $14           # unlinked
        ai      $3, $6, 16
        br      .Lmalloc_done
2:      ai      $5, $6, 4
        LDW     $6, $5
        br      1b
.Lmalloc_grow:
        ori     $17, $3, 0
        brsl    $0, sbrk
        ceqi    $4, $3, -1
        brnz    $4, .Lmalloc_fail
        STW     $17, $3, $13, $14
        ai      $3, $3, 16
        br      .Lmalloc_done
.Lmalloc_enomem:
        il      $3, ENOMEM
        ila     $5, errno
        STW     $3, $5, $8, $9
.Lmalloc_fail:
        il      $3, 0
.Lmalloc_done:
        ai      $1, $1, 32
        lqd     $0, 16($1)
        bi      $0
        .size   malloc, .-malloc

# void free(void *p): into the free list at its address, merged with the free blocks
# just after and just before it.
        .global free
        .type   free, @function
free:
        brz     $3, 9f
        ai      $3, $3, -16                 # the block
        ila     $5, .Lfree_list             # the link to update
        il      $4, 0                       # the free block before (none yet)
        LDW     $6, $5
1:      brz     $6, 2f
        clgt    $7, $3, $6
        brz     $7, 2f
        ori     $4, $6, 0
        ai      $5, $6, 4
        LDW     $6, $5
        br      1b
2:      ai      $8, $3, 4
        STW     $6, $8, $10, $11            # block.next = the one after
        STW     $3, $5, $10, $11            # the link before -> block
        LDW     $7, $3                      # block's size
        a       $9, $3, $7
        ceq     $9, $9, $6
        brz     $9, 3f
        brz     $6, 3f
        LDW     $12, $6                     # merge with the one after
        a       $7, $7, $12
        STW     $7, $3, $10, $11
        ai      $13, $6, 4
        LDW     $12, $13
        STW     $12, $8, $10, $11
3:      brz     $4, 9f
        LDW     $12, $4                     # merge into the one before
        a       $9, $4, $12
        ceq     $9, $9, $3
        brz     $9, 9f
        a       $12, $12, $7
        STW     $12, $4, $10, $11
        LDW     $13, $8
        ai      $14, $4, 4
        STW     $13, $14, $10, $11
9:      bi      $0
        .size   free, .-free

# void *calloc(size_t n, size_t size): n * size zeroed bytes; a product past 32 bits is
# ENOMEM.
        .global calloc
        .type   calloc, @function
calloc:
        stqd    $0, 16($1)
        stqd    $1, -64($1)
        ai      $1, $1, -64
        mpyu    $5, $3, $4                  # the low 32 bits of n * size
        mpyh    $6, $3, $4
        a       $5, $5, $6
        mpyh    $6, $4, $3
        a       $5, $5, $6
        stqd    $5, 32($1)
        brz     $3, 1f
        stqd    $4, 48($1)                  # n * size / n == size, or it overflowed
        ori     $4, $3, 0
        ori     $3, $5, 0
        brsl    $0, __udivsi3
        lqd     $4, 48($1)
        ceq     $6, $3, $4
        brnz    $6, 1f
        il      $3, -1                      # more than local store: malloc refuses
        br      2f
1:      lqd     $3, 32($1)
2:      brsl    $0, malloc
        brz     $3, 3f
        stqd    $3, 48($1)
        il      $4, 0
        lqd     $5, 32($1)
        brsl    $0, memset
        lqd     $3, 48($1)
3:      ai      $1, $1, 64
        lqd     $0, 16($1)
        bi      $0
        .size   calloc, .-calloc

# void *realloc(void *p, size_t n): malloc(n) for a null p; free(p) and 0 for n = 0; p
# itself while its block holds n bytes; else a new block with the old contents, p freed
# (and left as it was when there is no memory).
        .global realloc
        .type   realloc, @function
realloc:
        stqd    $0, 16($1)
        stqd    $1, -80($1)
        ai      $1, $1, -80
        brnz    $3, 1f
        ori     $3, $4, 0
        brsl    $0, malloc
        br      9f
1:      brnz    $4, 2f
        brsl    $0, free
        il      $3, 0
        br      9f
2:      ai      $5, $3, -16
        LDW     $6, $5
        ai      $6, $6, -16                 # what the block holds
        clgt    $7, $4, $6
        brz     $7, 9f
        stqd    $3, 32($1)
        stqd    $6, 48($1)
        ori     $3, $4, 0
        brsl    $0, malloc
        brz     $3, 9f
        stqd    $3, 64($1)
        lqd     $4, 32($1)
        lqd     $5, 48($1)
        brsl    $0, memcpy
        lqd     $3, 32($1)
        brsl    $0, free
        lqd     $3, 64($1)
9:      ai      $1, $1, 80
        lqd     $0, 16($1)
        bi      $0
        .size   realloc, .-realloc

        .section .rodata
        .align  4
.Lword1:                                    # shufb: $3's word 0 into word 1
        .long   0x10111213, 0x00010203, 0x18191a1b, 0x1c1d1e1f

        .data
        .align  4
.Lheap_end:
        .long   0, 0, 0, 0
.Lfree_list:
        .long   0, 0, 0, 0
