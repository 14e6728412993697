"""skinhil: real-time neuromorphic hardware-in-the-loop emulator of touch."""
