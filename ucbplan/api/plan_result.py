"""The :class:`Plan` that :func:`ucbplan.plan` returns, and :meth:`Plan.read` reads back.

A plan is its blocks table — the text table ``ucbplan plan -o plan.ecsv`` writes, with the run's
provenance, accounting, strategies and goals in its meta — and, when it was just made, the live
planner run. Everything a notebook reads comes from the table and its meta, so a plan read back
from its ECSV file answers the same: :attr:`Plan.table`, :attr:`~Plan.accounting`,
:attr:`~Plan.visits`, :attr:`~Plan.nights`, :attr:`~Plan.strategies`, :attr:`~Plan.goals`,
:attr:`~Plan.warnings`, ``len``, the reprs, :meth:`~Plan.plot`, :meth:`~Plan.charts`,
:meth:`~Plan.sheet`, :meth:`~Plan.export`, :meth:`~Plan.write` and :meth:`~Plan.to_astroplan`. Only
:attr:`Plan.run` (the planner's objects: targets, settings, blocks) is absent from a read plan, and
its charts and sheet draw no airmass or altitude limit (the constraint objects are the run's).

Every method works in the offline astropy scope (:func:`ucbplan.offline.offline`) and changes
nothing outside the plan; :attr:`Plan.table` is a converted copy of the ``plan -o`` text table.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from datetime import date
from functools import cached_property
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, TypeVar

from ucbplan.api._convert import scope
from ucbplan.api._plan_records import (
    GoalRecord,
    StrategyRecord,
    as_qtable,
    goals_of,
    strategies_of,
)
from ucbplan.core.constants import HOUR_S
from ucbplan.errors import InputError, InputFileError, PlanWarning, UcbplanError, emit, shorten

if TYPE_CHECKING:
    from collections.abc import Callable

    from astropy.table import QTable, Table
    from matplotlib.axes import Axes

    from ucbplan.observing.blocks.accounting import PlanAccount, VisitSummary
    from ucbplan.observing.constraints import ConstraintSet
    from ucbplan.observing.observatory.sites import Site
    from ucbplan.observing.schedule import PlanRun

T = TypeVar("T")
#: The site fields a plan's meta records (``Site.as_dict``).
_SITE_KEYS = ("name", "lon_deg", "lat_deg", "height_m", "timezone", "zenith_hole_deg")
#: Formats :meth:`Plan.write` writes (as ``plan -o``); :meth:`Plan.read` reads the first.
PLAN_FORMATS = ("ecsv", "csv", "json")


def _count(n: int, what: str) -> str:
    return f"{n} {what}{'' if n == 1 else 's'}"


def _path(value: Any, parameter: str) -> Path:
    """``value`` as a path (a str or os.PathLike).

    Raises
    ------
    InputError
        For anything else, naming ``parameter``.
    """
    if isinstance(value, str | os.PathLike) and str(value).strip() and "\0" not in str(value):
        return Path(value)
    raise InputError(
        f"{parameter}: expected a file path (str or pathlib.Path), got {shorten(value, 60)}",
        parameter=parameter,
    )


def _flag(value: Any, parameter: str) -> bool:
    """``value`` if it is a bool.

    Raises
    ------
    InputError
        For anything else, naming ``parameter``.
    """
    if isinstance(value, bool):
        return value
    raise InputError(f"{parameter}: expected True or False, got {shorten(value, 40)}", parameter)


@dataclass(frozen=True, eq=False)
class Plan:
    """A finished plan: the blocks table, visits, time accounting, strategies and goals.

    ``repr(plan)`` is one line (targets, nights, visits, exposures, hours); in a notebook the
    plan shows a summary table (:meth:`_repr_html_`); ``len(plan)`` is its number of exposures.

    Every attribute and method works on a plan read back with :meth:`read` as on the plan just
    made, except :attr:`run` (None: its charts and sheet draw no airmass or altitude limit, those
    being the run's constraint objects) and the aliases of its :attr:`site`.

    Attributes
    ----------
    run : PlanRun or None
        The planner's record (targets, site, nights, settings and result); None for a plan
        read from a file (:meth:`read`).
    source : astropy.table.Table or None
        The blocks table of a plan read from a file (None for a plan just made).
    """

    run: PlanRun | None = None
    source: Table | None = field(default=None, repr=False)
    #: The options :func:`ucbplan.plan` was called with, recorded in the meta (``plan_options``)
    #: so that :func:`ucbplan.replan` can plan again with them.
    options: dict[str, Any] | None = field(default=None, repr=False)
    #: The rows a replan keeps before its ``from_`` instant (the plan's history), first.
    history: Table | None = field(default=None, repr=False)

    # ------------------------------------------------------------------------------ tables

    @cached_property
    def text_table(self) -> Table:
        """The blocks table as ``ucbplan plan -o plan.ecsv`` writes it: times as ISO text (UTC at
        the site, TDB at the barycentre), numbers with units, provenance in ``meta``."""
        if self.run is None:
            if self.source is None:
                raise InputError("Plan: expected a planner run or a blocks table, got neither")
            return self.source
        with scope():
            table = self.run.table()
        if self.history is not None and len(self.history):
            from astropy.table import vstack

            meta = table.meta
            table = vstack([self.history, table], metadata_conflicts="silent")
            table.meta = meta
        if self.options is not None:
            table.meta["plan_options"] = dict(self.options)
        return table

    @cached_property
    def table(self) -> QTable:
        """The blocks table for Python: ``Time`` columns (``t_*_utc`` in UTC, ``t_mid_tdb_bary``
        in TDB; a blank ``t_alt_utc`` masked) and ``Quantity`` columns [units of
        docs/blocks-table.md]; names, local times and sexagesimal text as text. A copy of
        :attr:`text_table`, which is what the files hold."""
        with scope():
            return as_qtable(self.text_table)

    @property
    def meta(self) -> dict[str, Any]:
        """The table's provenance (site, targets, nights, exposure, planning, accounting …)."""
        return dict(self.text_table.meta)

    def _meta(self, key: str) -> Any:
        meta = self.text_table.meta
        if key not in meta:
            raise InputFileError(
                f"blocks table meta: expected {key!r} (as `ucbplan plan` writes it), got a "
                "table without; read a plan written by Plan.write or `ucbplan plan -o x.ecsv`"
            )
        return meta[key]

    def _typed(self, key: str, build: Callable[[Any], T]) -> T:
        """``build(meta[key])``; a value that does not build (a hand-edited file) is an
        :class:`InputFileError` naming ``key``."""
        value = self._meta(key)
        try:
            return build(value)
        except UcbplanError:
            raise
        except (TypeError, ValueError, KeyError, AttributeError) as exc:
            raise InputFileError(
                f"blocks table meta {key}: expected what `ucbplan plan` writes, got "
                f"{shorten(value, 60)} ({type(exc).__name__}); regenerate the plan"
            ) from None

    def __len__(self) -> int:
        """The number of exposures (Σ ``n_exp`` over the blocks)."""
        return int(sum(int(n) for n in self.text_table["n_exp"]))

    # ------------------------------------------------------------------------ typed records

    @cached_property
    def site(self) -> Site:
        """The observatory."""
        from ucbplan.observing.observatory.sites import Site

        if self.run is not None:
            return self.run.site
        return self._typed("site", lambda v: Site(**{k: v[k] for k in _SITE_KEYS if k in v}))

    @property
    def nights(self) -> list[date]:
        """The local dates of the evenings planned."""
        return self._typed("nights", lambda v: [date.fromisoformat(str(n)) for n in v])

    @cached_property
    def accounting(self) -> PlanAccount:
        """Time accounting, typed: the total and one account per target (visits, exposures,
        shutter, overheads, idle [s] to 1 ms, as the table's meta records it; efficiency);
        ``.as_meta()`` is the meta's dict."""
        from ucbplan.observing.blocks.accounting import PlanAccount, TimeAccount

        entry = self._meta("time_accounting")
        entry = entry if isinstance(entry, dict) else {}
        targets = entry.get("targets")
        return PlanAccount(
            TimeAccount.from_meta("total", entry.get("total")),
            {
                str(k): TimeAccount.from_meta(f"targets.{k}", v)
                for k, v in (targets.items() if isinstance(targets, dict) else ())
            },
        )

    @property
    def time_account(self) -> PlanAccount:
        """:attr:`accounting` (its earlier name)."""
        return self.accounting

    @cached_property
    def visits(self) -> list[VisitSummary]:
        """One summary per visit (acquisition + exposures; times to 1 ms, as the table's meta
        records them), in time order."""
        from ucbplan.observing.blocks.accounting import VisitSummary

        return self._typed("visits", lambda v: [VisitSummary(**dict(r)) for r in v])

    @property
    def strategies(self) -> tuple[StrategyRecord, ...]:
        """The exposure-strategy comparison of every target whose exposure time was chosen for
        information per visit (``plan``'s "Exposure strategy" table); empty otherwise."""
        meta = self.text_table.meta
        if "planning" not in meta:
            return ()
        with scope():
            return self._typed("planning", lambda _: strategies_of(meta))

    @property
    def goals(self) -> tuple[GoalRecord, ...]:
        """Each target's goal (``goal="sigma_K=5km/s"``) and the σ the plan promises."""
        meta = self.text_table.meta
        if "planning" not in meta:
            return ()
        with scope():
            return self._typed("planning", lambda _: goals_of(meta))

    @property
    def not_planned(self) -> dict[str, dict[str, dict[str, int]]]:
        """``{target: {night: {reason: count}}}`` of the night-time anchors not planned."""
        if self.run is not None:
            return dict(self.run.result.reasons)
        return self._typed("not_planned", lambda v: {str(k): dict(r) for k, r in v.items()})

    @property
    def warnings(self) -> list[str]:
        """The plan's warnings (also emitted as :class:`ucbplan.PlanWarning` when planned)."""
        if self.run is not None:
            return list(self.run.result.warnings)
        return self._typed("warnings", lambda v: [str(w) for w in v])

    # ------------------------------------------------------------------------------ reprs

    def _summary(self) -> dict[str, Any]:
        total = self.accounting.total
        return {
            "targets": len(self._meta("targets")),
            "nights": len(self._meta("nights")),
            "visits": total.visits,
            "exposures": len(self),
            "hours": total.total_s / HOUR_S,
        }

    def __repr__(self) -> str:
        s = self._summary()
        parts = [_count(s[k], k[:-1]) for k in ("targets", "nights", "visits", "exposures")]
        site = " ".join(self.site.name.split())
        site = site if len(site) <= 40 else f"{site[:39]}…"
        return f"<Plan at {site}: {', '.join(parts)}, {s['hours']:.2f} h>"

    def _repr_html_(self) -> str:
        """A summary table (Jupyter): the counts and hours, each goal's promised σ and each
        strategy's fraction of the best; every text escaped."""
        from ucbplan.api._plan_html import summary_html

        return summary_html(
            f"Plan at {self.site.name}", self._summary(), self.goals, self.strategies
        )

    # ---------------------------------------------------------------------------- figures

    def _constraints(self) -> ConstraintSet | None:
        return self.run.settings.constraints(self.run.site) if self.run is not None else None

    def plot(self, ax: Axes | None = None, *, night: date | str | None = None) -> Axes:
        """Night chart: altitude [deg] vs UTC, twilight shaded, the Moon and the visits.

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Draw one night into it (``night``, else the first). Without it, a new figure
            (matplotlib's current backend: inline in a notebook) with one panel per night, as
            ``plan --plot nights.png`` draws it, or one panel for ``night``.
        night : date or str, optional
            The night (local evening, ``YYYY-MM-DD``) to chart.

        Returns
        -------
        matplotlib.axes.Axes
            The (first) panel; save with ``ax.figure.savefig("nights.png")``.

        Raises
        ------
        InputError
            No blocks, a night the plan has no blocks on, or more nights than one figure holds
            (:data:`~ucbplan.observing.night.chart.MAX_PANELS`; give ``night`` or use
            :meth:`charts` with a PDF).
        """
        from ucbplan.observing.night.chart import plot_charts

        if ax is not None and not callable(getattr(ax, "axvspan", None)):
            raise InputError(
                f"ax: expected matplotlib Axes (or None), got {shorten(ax, 60)}", parameter="ax"
            )
        if night is not None and not isinstance(night, str | date):
            raise InputError(
                f"night: expected a date or YYYY-MM-DD text, got {shorten(night, 40)}", "night"
            )
        with scope():
            return plot_charts(self.text_table, self.site, self._constraints(), ax=ax, night=night)

    def charts(self, path: str | Path, *, overwrite: bool = False) -> int:
        """Write the night charts, as ``plan --plot PATH``: a ``.pdf`` page per night or a
        ``.png``/``.svg`` panel per night; the number of nights charted.

        Parameters
        ----------
        path : str or Path
            ``.pdf`` (a page per night), ``.png`` or ``.svg`` (one image, a panel per night).
        overwrite : bool
            Replace an existing ``path``.

        Returns
        -------
        int
            The nights charted.

        Raises
        ------
        InputError
            Another suffix, a plan without blocks, or too many nights for one image.
        OutputExistsError
            ``path`` exists and ``overwrite`` is false.
        """
        from ucbplan.observing.night.chart import write_night_charts

        with scope():
            return write_night_charts(
                self.text_table,
                self.site,
                _path(path, "path"),
                constraints=self._constraints(),
                overwrite=_flag(overwrite, "overwrite"),
            )

    def sheet(self, path: str | Path, *, overwrite: bool = False) -> int:
        """Write the night sheet (``.pdf`` or self-contained ``.html``), as ``plan --sheet``;
        the number of nights on it.

        Parameters
        ----------
        path : str or Path
            ``.pdf`` or ``.html``.
        overwrite : bool
            Replace an existing ``path``.

        Returns
        -------
        int
            The nights on the sheet.

        Raises
        ------
        InputError
            Another suffix, or a plan without blocks.
        OutputExistsError
            ``path`` exists and ``overwrite`` is false.
        """
        from ucbplan.observing.night.sheet import write_night_sheet

        with scope():
            return write_night_sheet(
                self.text_table,
                self.site,
                _path(path, "path"),
                constraints=self._constraints(),
                overwrite=_flag(overwrite, "overwrite"),
            )

    # ------------------------------------------------------------------------------ files

    def to_text(self, fmt: str = "ecsv") -> str:
        """The table as ``plan --format FMT`` prints it (``ecsv``, ``csv`` or ``json``).

        Parameters
        ----------
        fmt : str
            ``ecsv``, ``csv`` or ``json``.

        Returns
        -------
        str
            The text, ending in a newline.

        Raises
        ------
        InputError
            Another ``fmt``.
        """
        import io

        from ucbplan.observing.blocks.write import write_table

        if fmt not in PLAN_FORMATS:
            raise InputError(
                f"fmt: expected one of {', '.join(PLAN_FORMATS)}, got {shorten(fmt, 40)}",
                parameter="fmt",
            )
        buffer = io.StringIO()
        with scope():
            write_table(self.text_table, buffer, fmt, json_meta=True)
        return buffer.getvalue()

    def to_dict(self) -> dict[str, Any]:
        """The document ``plan --format json`` prints, without a JSON text round trip.

        Returns
        -------
        dict
            ``{"meta": {...}, "rows": [{column: value}, ...]}`` in plain values (NaN → None).
        """
        from ucbplan.io import json_plain
        from ucbplan.observing.blocks.write import table_to_json_rows

        table = self.text_table
        doc: dict[str, Any] = json_plain({"meta": dict(table.meta)})
        doc["rows"] = table_to_json_rows(table)
        return doc

    def write(self, path: str | Path, fmt: str | None = None, overwrite: bool = False) -> Path:
        """Write the blocks table (``.ecsv``, ``.csv`` or ``.json``, as ``plan -o``), atomically;
        :meth:`read` reads an ECSV file back.

        Parameters
        ----------
        path : str or Path
            The file; its suffix picks the format unless ``fmt`` is given.
        fmt : str, optional
            ``ecsv``, ``csv`` or ``json``.
        overwrite : bool
            Replace an existing ``path``.

        Returns
        -------
        Path
            ``path``.

        Raises
        ------
        InputError
            An unknown ``fmt``.
        OutputExistsError
            ``path`` exists and ``overwrite`` is false.
        """
        from ucbplan.io import output_format, write_output
        from ucbplan.observing.blocks.write import write_table

        out = _path(path, "path")
        if fmt is not None and fmt not in PLAN_FORMATS:
            raise InputError(
                f"fmt: expected one of {', '.join(PLAN_FORMATS)}, got {shorten(fmt, 40)}",
                parameter="fmt",
            )
        kind = output_format(out, fmt, PLAN_FORMATS, "ecsv")
        table = self.text_table

        def _write(handle: IO[str]) -> None:
            write_table(table, handle, kind, json_meta=True)

        with scope():
            write_output(out, _write, overwrite=_flag(overwrite, "overwrite"))
        return out

    @classmethod
    def read(cls, path: str | Path) -> Plan:
        """A plan written by :meth:`write` (or ``ucbplan plan -o plan.ecsv``): the same table,
        meta, accounting, visits, strategies and goals; no :attr:`run`.

        Parameters
        ----------
        path : str or Path
            An ECSV blocks table with the plan's meta.

        Returns
        -------
        Plan
            The plan, without the live run.

        Raises
        ------
        InputFileError
            Not a readable ECSV blocks table with the plan's meta (CSV and JSON files hold the
            rows only: write ECSV to read a plan back).
        """
        from ucbplan.observing.blocks.read import read_blocks

        with scope():
            table = read_blocks(_path(path, "path"))
        if "time_accounting" not in table.meta:
            raise InputFileError(
                f"{shorten(str(path), 80)}: expected an ECSV plan with its meta (Plan.write or "
                "`ucbplan plan -o plan.ecsv`), got a table without; write the plan as .ecsv"
            )
        return cls(None, table)

    def export(
        self,
        to: str,
        path: str | Path | None = None,
        *,
        overwrite: bool = False,
        acquisition_s: float | None = None,
        tolerance_sigma: float | None = None,
        tolerance_floor_s: float | None = None,
        merge_overlaps: bool | None = None,
        proposal_format: str | None = None,
        keck_rotmode: str | None = None,
        force: bool | None = None,
        semester: str | None = None,
        seeing_arcsec: float | None = None,
        instrument: str | None = None,
        eso_templates: str | Path | None = None,
    ) -> str | Path:
        """The plan exported as ``ucbplan export plan.ecsv --to TO`` writes it.

        Parameters
        ----------
        to : str
            ``eso-p2``, ``keck-starlist``, ``ics``, ``proposal``, ``ing-cat``, ``lco``,
            ``gemini`` or ``phase-table``.
        path : str or Path, optional
            Write the export there (atomically) and return the path; without it, return the
            text the command prints.
        overwrite : bool
            Replace an existing ``path``.
        acquisition_s, tolerance_sigma, tolerance_floor_s, merge_overlaps, proposal_format, \
keck_rotmode, force, semester, seeing_arcsec, instrument, eso_templates
            As :class:`~ucbplan.observing.exports.ExportOptions` (None: its default, the
            command's); ``proposal_format`` defaults to the suffix of ``path``, else ``ecsv``.

        Returns
        -------
        str or Path
            The export's text (no ``path``), else ``path``.

        Raises
        ------
        UcbplanError
            A bad ``to`` or option, a site ``to`` does not serve (SiteError), ``path`` exists.

        Warns
        -----
        PlanWarning
            The notes the command prints (defaults taken, rounding).
        """
        from ucbplan.api._plan_export import export_plan

        given = {k: v for k, v in locals().items() if k not in ("self", "to", "path", "overwrite")}
        out = None if path is None else _path(path, "path")
        with scope():
            content, notes = export_plan(
                self.text_table, to, out, _flag(overwrite, "overwrite"), given
            )
        emit(list(notes), PlanWarning)
        return content

    def to_astroplan(self) -> Any:
        """The plan as an ``astroplan.Schedule`` (docs/exports.md).

        Returns
        -------
        astroplan.Schedule
            One ``ObservingBlock`` per exposure with the plan's constraints and its window.

        Raises
        ------
        InputError
            astroplan is not installed (``pip install 'ucbplan[astroplan]'``).
        """
        from ucbplan.observing.exports.astroplan_schedule import to_astroplan

        with scope():
            return to_astroplan(self.text_table, self.site)
