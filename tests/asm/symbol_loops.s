# Symbols defined in terms of each other (gas's resolve_symbol_value: "symbol definition
# loop encountered"), reported where the loop closes.
	.set a, b
	.set b, a		# error: 4:1: symbol definition loop encountered at `b'
	c = c + 1		# error: 5:1: symbol definition loop encountered at `c'
	.set x, y		# a forward reference that is no loop
	.set y, 1
	.long x
