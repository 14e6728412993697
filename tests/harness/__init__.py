"""Helpers shared by the board, serve and transport tests (real ptys, real CAN buses)."""
