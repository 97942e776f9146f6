# Sources GNU as 2.40 accepts with a warning (read.c emit_expr, expr.c): each warning at
# its operand, the bytes GNU stores, and the assembly succeeds.
	.data
	.long 7/0		# => 00000007
# warning: 4:8: division by zero
	.set q, 9/0
# warning: 6:10: division by zero
	.long q			# => 00000009
	.long 10%0		# => 00000000
# warning: 9:8: division by zero
	.byte 256		# => 00
# warning: 11:8: value 0x100 truncated to 0x0
	.byte 1, 0x1ff, 3	# => 01ff03
# warning: 13:11: value 0x1ff truncated to 0xff
	.long 1<<40		# => 00000000
# warning: 15:8: value 0x10000000000 truncated to 0x0
	.short -32768, -1, 65535, 0x12345	# => 8000ffffffff2345
# warning: 17:28: value 0x12345 truncated to 0x2345
	.byte -1, 255, -128, -256	# => ffff8000
# warning: 19:23: value 0xffffffffffffff00 truncated to 0x0
	.byte -257		# => ff
# warning: 21:8: value 0xfffffffffffffeff truncated to 0xff
	.quad 1<<40		# => 0000010000000000
	.space 0
# warning: 24:2: .space repeat count is zero, ignored
	.skip -4
# warning: 26:2: .space repeat count is negative, ignored
	.fill -1, 4, 9
# warning: 28:2: repeat < 0; .fill ignored
	.fill 1, -2, 9
# warning: 30:2: size negative; .fill ignored
	.fill 1, 9, 0x11	# => 0000001100000000
# warning: 32:2: .fill size clamped to 8
	.byte 0x77		# => 77
