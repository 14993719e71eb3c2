"""What a user reads or opens (layer 5): the liaison force report, descriptions of a model and
a state, figures on ``matplotlib.figure.Figure``, VTK files.

Names are imported when first used (matplotlib only with a figure). The two atomic writers live
in ``hexapod._support.files`` (layer 0) and are public here.
"""

from hexapod._support.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod.output.report": ["FOOT_MARKER", "RunInfo", "agreement", "figure_builders",
                              "report_files", "wrench_label"],
    "hexapod.output.actuation": ["MotorCheck", "check_motors"],
    "hexapod.output.motor_figures": ["envelope_figure"],
    "hexapod.output.stability": ["Stability", "signed_distance", "stability_figure",
                                 "stability_margins"],
    "hexapod.output.inverse_csv": ["inverse_columns", "inverse_csv_text", "inverse_table"],
    "hexapod.output.describe": ["describe_model", "describe_state", "format_model",
                                "format_state"],
    "hexapod.output.figures": ["COMPONENT_COLOURS", "effort_figure", "png_bytes",
                               "prepare_drawing", "render_figures", "trajectory_figure",
                               "wrench_figure"],
    "hexapod.output.contact_figures": ["contact_figure_builders", "pushed_intervals",
                                       "tracking_figure", "tracking_figure_builders"],
    "hexapod._support.files": ["write_atomically", "write_directory_atomically"],
})
