"""The studies wing: one analysis over a grid or a random sample of scene or physical
parameters, on local processes or a Dask cluster, resumable, as one tidy table
(``fsicas study STUDY.toml``; docs/studies.md)."""

from .analyses import study_point
from .run import TABLE_FORMATS, check_table_path, run_study, write_table
from .spec import ANALYSES, DISTRIBUTIONS, SETTINGS, Study, load_study
from .summary import summarize

__all__ = ["Study", "load_study", "run_study", "write_table", "study_point",
           "check_table_path", "summarize", "ANALYSES", "DISTRIBUTIONS", "SETTINGS", "TABLE_FORMATS"]
