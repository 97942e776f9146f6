# Data directives: sizes, byte order, strings, fill.
	.data
d:	.byte 1, 2, -1, 255	# => 0102ffff
	.byte 'A, 'a+1		# => 4162
	.half 0x1234, -2	# => 1234fffe
	.short 0x5678		# => 5678
	.hword 7		# => 0007
	.int 0x01020304		# => 01020304
	.long -1		# => ffffffff
	.word 0xdeadbeef	# => deadbeef
	.quad 0x0102030405060708 # => 0102030405060708
	.quad -2		# => fffffffffffffffe
	.float 1.5		# => 3fc00000
	.float -2.0, 0.1	# => c0000000 3dcccccd
	.double 1.5		# => 3ff8000000000000
	.double -0.1		# => bfb999999999999a
	.string "ab"		# => 616200
	.ascii "a\n\t\"\\"	# => 610a09225c
	.asciz "xy", "z"	# => 7879007a00
	# KNOWN GAP: "\x41" and octal "\101" escapes come out as "x4" and "10"
	.space 3		# => 000000
	.space 2, 0xaa		# => aaaa
	.skip 2, 7		# => 0707
	.fill 3, 2, 0x1234	# => 123412341234
	.fill 2, 1, 9		# => 0909
	.fill 1, 4, 0x55	# => 00000055
	.fill 2			# => 0000
	.byte 0xcc		# => cc
