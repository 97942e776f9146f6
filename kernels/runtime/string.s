# string.s: the memory and string functions compiled code calls without asking for them
# (spu-gcc emits memcpy and memset for structure copies and clears), one byte at a time:
# small, not fast. Each byte is moved as the SPU must: load its quadword, rotate the byte
# to the preferred byte slot (3), insert it into the destination quadword with a cbd mask.

        .text
# void *memcpy(void *dst, const void *src, size_t n), memmove: the same, backwards when
# the destination lies above the source.
        .global memcpy
        .type   memcpy, @function
        .global memmove
        .type   memmove, @function
memcpy:
memmove:
        ori     $6, $3, 0               # destination cursor
        ori     $10, $4, 0              # source cursor
        il      $11, 1                  # step
        clgt    $12, $3, $4             # dst > src: copy from the end
        brz     $12, 1f
        a       $6, $6, $5
        ai      $6, $6, -1
        a       $10, $10, $5
        ai      $10, $10, -1
        il      $11, -1
1:      brz     $5, 2f
        lqd     $7, 0($10)
        ai      $8, $10, -3
        rotqby  $7, $7, $8              # the byte into slot 3
        lqd     $9, 0($6)
        cbd     $8, 0($6)
        shufb   $9, $7, $9, $8
        stqd    $9, 0($6)
        a       $6, $6, $11
        a       $10, $10, $11
        ai      $5, $5, -1
        br      1b
2:      bi      $0
        .size   memcpy, .-memcpy

# void *memset(void *dst, int c, size_t n)
        .global memset
        .type   memset, @function
memset:
        ori     $6, $3, 0
1:      brz     $5, 2f
        lqd     $9, 0($6)
        cbd     $8, 0($6)
        shufb   $9, $4, $9, $8
        stqd    $9, 0($6)
        ai      $6, $6, 1
        ai      $5, $5, -1
        br      1b
2:      bi      $0
        .size   memset, .-memset

# size_t strlen(const char *s)
        .global strlen
        .type   strlen, @function
strlen:
        ori     $6, $3, 0
1:      lqd     $7, 0($6)
        ai      $8, $6, -3
        rotqby  $7, $7, $8
        andi    $7, $7, 0xff
        brz     $7, 2f
        ai      $6, $6, 1
        br      1b
2:      sf      $3, $3, $6
        bi      $0
        .size   strlen, .-strlen

# int strcmp(const char *a, const char *b): the difference of the first bytes that
# differ, as unsigned chars.
        .global strcmp
        .type   strcmp, @function
strcmp:
1:      lqd     $7, 0($3)
        ai      $8, $3, -3
        rotqby  $7, $7, $8
        andi    $7, $7, 0xff
        lqd     $9, 0($4)
        ai      $8, $4, -3
        rotqby  $9, $9, $8
        andi    $9, $9, 0xff
        sf      $10, $9, $7
        brnz    $10, 2f
        brz     $7, 2f
        ai      $3, $3, 1
        ai      $4, $4, 1
        br      1b
2:      ori     $3, $10, 0
        bi      $0
        .size   strcmp, .-strcmp

# char *strcpy(char *dst, const char *src)
        .global strcpy
        .type   strcpy, @function
strcpy:
        ori     $6, $3, 0
1:      lqd     $7, 0($4)
        ai      $8, $4, -3
        rotqby  $7, $7, $8
        lqd     $9, 0($6)
        cbd     $8, 0($6)
        shufb   $9, $7, $9, $8
        stqd    $9, 0($6)
        andi    $7, $7, 0xff
        ai      $4, $4, 1
        ai      $6, $6, 1
        brnz    $7, 1b
        bi      $0
        .size   strcpy, .-strcpy

# int memcmp(const void *a, const void *b, size_t n): the difference of the first bytes
# that differ, as unsigned chars; 0 when the n bytes are equal.
        .global memcmp
        .type   memcmp, @function
memcmp:
1:      brz     $5, 2f
        lqd     $7, 0($3)
        ai      $8, $3, -3
        rotqby  $7, $7, $8
        andi    $7, $7, 0xff
        lqd     $9, 0($4)
        ai      $8, $4, -3
        rotqby  $9, $9, $8
        andi    $9, $9, 0xff
        sf      $10, $9, $7
        brnz    $10, 3f
        ai      $3, $3, 1
        ai      $4, $4, 1
        ai      $5, $5, -1
        br      1b
2:      il      $3, 0
        bi      $0
3:      ori     $3, $10, 0
        bi      $0
        .size   memcmp, .-memcmp
