"""Seed 000's joint-coordinate forms ``W(q) q_dd = P + V`` of open chains (layer 3)."""
