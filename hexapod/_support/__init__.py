"""Layer 0 helpers with no mechanics: buffered CasADi calls, graphs, atomic files."""
