"""Reports: accuracy figures of merit, matplotlib figures, HTML + JSON documents.

`metrics` (position error and ballbar statistics), `figures` (each plot with its
data), `document` (Report, Table, write_report), `accuracy` (the before/after
report of a fitted model).
"""

from typing import TYPE_CHECKING

from rapidfix import lazy_exports

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.report.accuracy import (
        BallbarRun,
        BeforeAfter,
        accuracy_report,
        validation_section,
    )
    from rapidfix.report.document import Report, Table, write_report
    from rapidfix.report.figures import (
        AFTER_COLOUR,
        BEFORE_COLOUR,
        Figure,
        finite_list,
        png_bytes,
        position_error_figure,
    )
    from rapidfix.report.metrics import ballbar_deviation, position_error_stats

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "AFTER_COLOUR": "figures",
    "BEFORE_COLOUR": "figures",
    "BallbarRun": "accuracy",
    "BeforeAfter": "accuracy",
    "Figure": "figures",
    "Report": "document",
    "Table": "document",
    "accuracy_report": "accuracy",
    "ballbar_deviation": "metrics",
    "finite_list": "figures",
    "png_bytes": "figures",
    "position_error_figure": "figures",
    "position_error_stats": "metrics",
    "validation_section": "accuracy",
    "write_report": "document",
}

__all__ = [
    "AFTER_COLOUR",
    "BEFORE_COLOUR",
    "BallbarRun",
    "BeforeAfter",
    "Figure",
    "Report",
    "Table",
    "accuracy_report",
    "ballbar_deviation",
    "finite_list",
    "png_bytes",
    "position_error_figure",
    "position_error_stats",
    "validation_section",
    "write_report",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
