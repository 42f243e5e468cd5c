"""One clip through every stage it needs, then committed: :func:`process_clip`."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from handdb.build import progress
from handdb.build.context import BuildContext, StageFailed
from handdb.build.keys import MARKER_FIT_STAGES, STAGES
from handdb.build.plan import PlannedClip
from handdb.build.reload import resume
from handdb.build.rows import clip_tables
from handdb.build.stages import (
    ClipRefused,
    ClipResult,
    export,
    fill,
    fit_marker_clip,
    ingest,
    lift_clip,
    resolve_bone_lengths,
    validate,
)
from handdb.errors import InputError
from handdb.store.quarantine import Refusal

#: What progress calls a marker clip's bone-length stage, which is its whole model fit
#: (:data:`~handdb.build.keys.MARKER_FIT_STAGES`), the longest stage of any clip.
MODEL_FIT_PROGRESS = "model_fit"


def _progress_stage(item: PlannedClip, stage: str) -> str:
    """The name progress shows for ``stage`` of ``item``."""
    return MODEL_FIT_PROGRESS if item.markers and stage == MARKER_FIT_STAGES[0] else stage


def _refusal(refused: ClipRefused, clip_id: str, sidecar: str, stage: str) -> Refusal:
    error = refused.error
    if isinstance(error, InputError):
        return Refusal.from_error(error, clip_id=clip_id)
    return Refusal(file=sidecar, reason=str(error), error_type=type(error).__name__,
                   field=refused.field, clip_id=clip_id, stage=stage)


def _internal_refusal(error: Exception, clip_id: str, sidecar: str, stage: str) -> Refusal:
    """A clip a stage broke on: refused with what happened, blaming no key of its files."""
    return Refusal(
        file=sidecar, error_type=type(error).__name__, clip_id=clip_id, stage=stage,
        reason=f"{progress.STAGE_WORK[stage]} failed on this clip "
               f"({type(error).__name__}: {error}); its files were read, but handdb could not "
               "process them: the clip's stored rows are kept, and the fault is handdb's, "
               "please report it with the clip")


def _stage_runners(context: BuildContext, markers: bool
                   ) -> dict[str, Callable[[ClipResult], ClipResult]]:
    options = context.options
    runners: dict[str, Callable[[ClipResult], ClipResult]] = {
        "lengths": lambda r: resolve_bone_lengths(r, context.ratios),
        "gap_fill": lambda r: fill(r, options),
        "lift": lambda r: lift_clip(r, options),
        "validate": lambda r: validate(r, options),
        "export": lambda r: export(r, context.store, options),
    }
    if markers:
        runners.update(dict.fromkeys(MARKER_FIT_STAGES, lambda r: r))
        runners["lengths"] = fit_marker_clip
    return runners


def first_stage(item: PlannedClip) -> str:
    """The stage :func:`process_clip` starts ``item`` at.

    The plan's first changed stage (the first of all for a current clip), moved back to
    the model fit for a marker clip, whose bone lengths, gap filling and lifting are one fit.
    """
    start = item.start or STAGES[0]
    if item.markers and STAGES.index(start) > STAGES.index(MARKER_FIT_STAGES[0]):
        start = MARKER_FIT_STAGES[0]
    return start


def process_clip(item: PlannedClip, context: BuildContext) -> ClipResult | Refusal:
    """Run the stages ``item`` needs, from its first changed one, and commit the clip.

    Stages before ``item.start`` are read back from the store. A marker clip's bone
    lengths, gap filling and lifting are one model fit, redone whenever any of them or
    anything after them is.

    Returns
    -------
    ClipResult or Refusal
        The committed result, or why the clip's input was refused (nothing is committed
        then, and the clip's stored rows stay as they were).

    Raises
    ------
    StageFailed
        When writing into the database fails (an ``OSError``); any other error refuses
        the clip, naming the stage.
    """
    clip_id = item.entry.clip_id
    start = first_stage(item)
    stage = start
    try:
        progress.started(clip_id, _progress_stage(item, stage))
        if start == STAGES[0]:
            result = ClipResult(clip=ingest(item.entry, item.content_hash), keys=item.keys)
        else:
            result = resume(context.store, item.entry, item.content_hash, item.keys, start)
        runners = _stage_runners(context, item.markers)
        for stage in STAGES[STAGES.index(start):]:
            if stage == STAGES[0]:
                continue
            progress.started(clip_id, _progress_stage(item, stage))
            result = runners[stage](result)
        stage = "commit"
        progress.started(clip_id, stage)
        context.store.commit_clip(clip_id, clip_tables(result, Path(context.inbox)))
    except ClipRefused as refused:
        return _refusal(refused, clip_id, str(item.entry.sidecar), stage)
    except OSError as error:
        raise StageFailed(clip_id, stage, error) from error
    except Exception as error:  # noqa: BLE001 - any other error refuses the clip, named
        return _internal_refusal(error, clip_id, str(item.entry.sidecar), stage)
    return result
