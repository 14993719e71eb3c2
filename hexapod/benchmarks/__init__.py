"""The cases with independent references and the studies on them (layer 6): the extreme-case
check and the work-precision study."""
