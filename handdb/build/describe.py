"""What a build and each of its clips did, in words, for an orchestrator's run pages.

An orchestrator shows a build as a run with a name, a final state and a log; these pure
functions word them from the plan and the :class:`~handdb.build.run.BuildSummary`, so that
every orchestrator tells the same story: :func:`clip_line` for each clip's log line,
:func:`planned_run_name` and :func:`run_name` for the run's name, before and after, and
:func:`run_outcome` for its final state.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from handdb.build.context import StageFailed
from handdb.build.keys import STAGES
from handdb.build.plan import BuildPlan, PlannedClip
from handdb.build.process import first_stage
from handdb.build.run import BuildSummary
from handdb.build.stages import ClipResult
from handdb.store.quarantine import Refusal

#: The stage that stores a clip's tables, after every stage of :data:`STAGES`.
COMMIT_STAGE = "commit"

#: Clips named in a failed run's message; the rest are counted.
NAMED_FAILURES = 3


def stages_run(item: PlannedClip) -> tuple[str, ...]:
    """The stages a build runs on ``item``, from its first changed one to the commit.

    Stages before the first are read back from the store.
    """
    start = first_stage(item)
    return (*STAGES[STAGES.index(start):], COMMIT_STAGE)


def clip_line(item: PlannedClip, outcome: ClipResult | Refusal | StageFailed) -> str:
    """One log line saying what the build did with ``item``: stages run, refused, failed.

    A processed clip's line names the stages that ran, its frames and, when it was flagged
    as implausible or its depth pose is as likely mirrored, why.
    """
    clip_id = item.clip_id
    if isinstance(outcome, StageFailed):
        return f"clip {clip_id} failed at {outcome}"
    if isinstance(outcome, Refusal):
        stage = f" at {outcome.stage}" if outcome.stage else ""
        return f"clip {clip_id} refused{stage}: {outcome}"
    stages = stages_run(item)
    read_back = "" if stages[0] == STAGES[0] else " (earlier stages read back)"
    line = (f"clip {clip_id}: ran {', '.join(stages)}{read_back}; "
            f"{outcome.clip.n_frames} frames")
    if outcome.verdict is not None and outcome.verdict.flagged:
        line += f"; flagged: {'; '.join(outcome.verdict.reasons)}"
    if outcome.lifted is not None and outcome.lifted.mirror_ambiguous:
        line += f"; depth ambiguous: {outcome.lifted.note}"
    return line


def _clips(n: int) -> str:
    return f"{n} clip{'' if n == 1 else 's'}"


def _counted(counts: list[tuple[int, str]], nothing: str) -> str:
    parts = [f"{n} {what}" for n, what in counts if n]
    return ", ".join(parts) or nothing


def planned_run_name(plan: BuildPlan) -> str:
    """The run's name when it starts, from its plan: ``build 12 clips (3 to process)``."""
    refused = len(plan.refusals) + len(plan.xray.refusals)
    todo = _counted([(len(plan.todo), "to process"), (refused, "refused")], "nothing to do")
    return f"build {_clips(len(plan.clips))} ({todo})"


def run_name(summary: BuildSummary) -> str:
    """The run's name once it is done: ``build 12 clips (3 processed, 1 refused)``."""
    done = _counted([(len(summary.processed), "processed"), (len(summary.refusals), "refused"),
                     (len(summary.failed), "failed")], "nothing new")
    return f"build {_clips(summary.n_clips)} ({done})"


class OutcomeKind(StrEnum):
    """How a build ended, worst last."""

    completed = "completed"
    refusals = "refusals"
    failed = "failed"


@dataclass(frozen=True)
class RunOutcome:
    """A build's final state: its kind, a short name and a message for the run's page."""

    kind: OutcomeKind
    name: str
    message: str


#: The state name of each outcome.
OUTCOME_NAMES: dict[OutcomeKind, str] = {
    OutcomeKind.completed: "Completed",
    OutcomeKind.refusals: "Completed with refusals",
    OutcomeKind.failed: "Failed",
}


def run_outcome(summary: BuildSummary) -> RunOutcome:
    """How the build ended: failed if any clip failed, else with refusals if any input was.

    Refused input is the user's to fix and the rest of the build stands, so a build with
    refusals completes, under a name that says so; a clip a stage failed on (the database's
    storage at fault) fails the build, as the ``runs`` row's ``status`` does.

    The message counts, worst first: ``1 of 9 clips failed (alpha); 2 inputs refused;
    6 of 9 clips processed, 0 unchanged``.
    """
    n = summary.n_clips
    parts = []
    if summary.failed:
        names = sorted(summary.failed)
        named = ", ".join(names[:NAMED_FAILURES])
        more = f" and {len(names) - NAMED_FAILURES} more" if len(names) > NAMED_FAILURES else ""
        parts.append(f"{len(names)} of {_clips(n)} failed ({named}{more})")
    if summary.refusals:
        k = len(summary.refusals)
        parts.append(f"{k} input{'' if k == 1 else 's'} refused (see the quarantine table)")
    parts.append(f"{len(summary.processed)} of {_clips(n)} processed, "
                 f"{len(summary.unchanged)} unchanged")
    kind = (OutcomeKind.failed if summary.failed else
            OutcomeKind.refusals if summary.refusals else OutcomeKind.completed)
    return RunOutcome(kind=kind, name=OUTCOME_NAMES[kind], message="; ".join(parts))
