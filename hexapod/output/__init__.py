"""What a user reads or opens (layer 5): the liaison force report, descriptions of a model and
a state, figures on ``matplotlib.figure.Figure``, VTK files."""
