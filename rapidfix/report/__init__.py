"""Reports: accuracy figures of merit, matplotlib figures, HTML + JSON documents.

`metrics` (position error and ballbar statistics), `figures` (each plot with its
data), `document` (Report, Table, write_report), `accuracy` (the before/after
report of a fitted model).
"""
