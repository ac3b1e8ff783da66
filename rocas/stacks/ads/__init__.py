"""The built-in ADS under test: parameters, modules and the stack that wires them."""
