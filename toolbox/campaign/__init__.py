"""Robustness campaigns: Monte-Carlo closed-loop qualification on Dask.

The ``[campaign]`` table of a spec (read by :mod:`toolbox.spec`) says how the
true plants are drawn; the spec's scenarios and requirements say what each
sample runs and when it fails. :func:`run_campaign` designs the controller
once, splits the samples into chunks, evaluates the chunks with the compiled
batch simulator on a Dask cluster (a LocalCluster by default, or an existing
one), writes one Parquet file per chunk and, at the end, ``results.parquet``,
``summary.json`` and ``report.html`` (toolbox/ARCHITECTURE.md "Campaigns").

Dask, pyarrow, scipy and matplotlib are imported only when a campaign runs
(``cct --help`` stays light).
"""

from ._cluster import parse_address
from ._evaluate import DIVERGED, Plan, evaluate_chunk, judge_rows, make_plan, scenario_slug
from ._run import (CAMPAIGN_SCHEMA, CHUNK_ATTEMPTS, CampaignRun, campaign_hash, chunk_path,
                   chunk_size, read_results, run_campaign, valid_chunks)
from ._sampling import draw_samples
from ._summary import parameter_columns, summarize, wilson_interval

__all__ = ["DIVERGED", "Plan", "evaluate_chunk", "judge_rows", "make_plan", "scenario_slug",
           "CAMPAIGN_SCHEMA", "CHUNK_ATTEMPTS", "chunk_size", "CampaignRun", "campaign_hash",
           "chunk_path", "read_results", "run_campaign", "valid_chunks", "draw_samples",
           "parameter_columns", "summarize", "wilson_interval", "parse_address"]
