"""``handdb ratios``: joint placement from X-ray statistics (Chaudhry et al.).

``place`` prints the expected segment lengths of a finger of known total length with
their min/max bands; ``show`` prints the ratio table and the paper's two discrepancies.
Both read ``joint_ratios`` from the database when it has that table, else use the
paper's Table 1 shipped with handdb.
"""

from __future__ import annotations

import pyarrow as pa
import pyarrow.compute as pc
import typer
from rich.console import Console
from rich.table import Table

from handdb.errors import HanddbError
from handdb.ingest.xray import SEGMENTS
from handdb.lengths.ratios import (
    ALL_COHORT,
    paper_discrepancies,
    place_joints,
    table1_ratios,
)
from handdb.paths import DEFAULT_DB
from handdb.store.database import Store

app = typer.Typer(name="ratios", help="Relative phalanx lengths from X-ray images and "
                  "joint placement (Chaudhry et al.).", no_args_is_help=True,
                  add_completion=False)
out = Console()

DbOption = typer.Option(DEFAULT_DB, "--db", envvar="HANDDB_DB",
                        help="Database to read joint_ratios from (else the paper's Table 1).")
CohortOption = typer.Option(ALL_COHORT, help="Cohort: all, sex:<value>, age:<band>.")


def load_ratios(db: str) -> tuple[pa.Table, str]:
    """Return table ``joint_ratios`` of database ``db``, else the paper's, and its origin."""
    stored = Store(db).read_table("joint_ratios")
    if stored.num_rows:
        return stored, f"database {db}"
    return table1_ratios(), "Chaudhry et al., Table 1"


@app.command()
def place(
    finger: str = typer.Option(..., help=f"One of {', '.join(SEGMENTS)}."),
    total: float = typer.Option(..., min=0.0, help="The finger's total length, any unit."),
    db: str = DbOption,
    cohort: str = CohortOption,
) -> None:
    """Print the expected segment lengths of a finger of known length, with bands."""
    ratios, origin = load_ratios(db)
    try:
        segments = place_joints(finger, total, ratios, cohort)
    except HanddbError as exc:
        raise typer.BadParameter(str(exc)) from None
    grid = Table("segment", "from root", "mean", "min", "max", "range",
                 title=f"{finger} finger of length {total:g}, cohort {cohort}")
    for s in segments:
        grid.add_row(s.segment, *(f"{v:.1f}" for v in (s.start, s.mean, s.min, s.max, s.range)))
    out.print(grid)
    out.print(f"ratios from {origin}", soft_wrap=True)


@app.command()
def show(db: str = DbOption, cohort: str = CohortOption) -> None:
    """Print the relative segment lengths and where the paper errs."""
    ratios, origin = load_ratios(db)
    rows = ratios.filter(pc.equal(ratios.column("cohort"), cohort))
    grid = Table("finger", "segment", "n", "mean", "min", "max", "range", "std", "95% CI",
                 title=f"joint ratios, cohort {cohort}")
    # fingers from the thumb to the little finger, not as stored (alphabetically)
    for r in sorted(rows.to_pylist(), key=lambda r: (list(SEGMENTS).index(r["finger"]),
                                                     r["segment"])):
        interval = "" if r["ci_low"] is None else f"{r['ci_low']:.4f}-{r['ci_high']:.4f}"
        std = "" if r["std"] is None else f"{r['std']:.4f}"
        grid.add_row(r["finger"], r["segment"], str(r["n"]),
                     *(f"{r[k]:.4f}" for k in ("mean", "min", "max", "range")), std, interval)
    out.print(grid)
    out.print(f"ratios from {origin}", soft_wrap=True)
    out.print("[bold]Where Chaudhry et al. contradict their Table 1:[/]")
    for discrepancy in paper_discrepancies():
        out.print(f"  - {discrepancy}")
