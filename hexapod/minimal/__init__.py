"""The joint-coordinate forms ``W(q) q_dd = P + V`` of Vukobratović and Potkonjak for open
chains (layer 3)."""
