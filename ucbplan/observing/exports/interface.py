"""What the export formats share: their options, their result and their signature."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from astropy.table import Table

from ucbplan.core.constants import DAY_S
from ucbplan.errors import InputError, shorten
from ucbplan.inputs import check_range
from ucbplan.observing.blocks.block import MAX_BLOCK_S
from ucbplan.observing.observatory.semesters import semester_dates

#: Acquisition overhead assumed when neither ``--acquisition`` nor an ``acq_s`` column is given [s]
#: (a typical VLT/Keck slit acquisition of a faint target: pointing, acquisition image, centring).
DEFAULT_ACQUISITION_S = 600.0

#: Largest window half-width in units of σ_t.
MAX_TOLERANCE_SIGMA = 100.0
#: Rotator modes a Keck starlist takes (``rotmode=``; ``vertical`` keeps the slit parallactic).
KECK_ROTMODES = ("pa", "vertical", "stationary")


@dataclass(frozen=True, slots=True)
class ExportOptions:
    """Knobs shared by the export formats.

    Attributes
    ----------
    acquisition_s : float or None
        Acquisition overhead before the first exposure [s]; None → ``acq_s`` column, else the
        plan's ``meta['overhead_s']``, else :data:`DEFAULT_ACQUISITION_S`.
    tolerance_sigma : float
        Window half-width in units of σ_t (k in k·σ_t).
    tolerance_floor_s : float
        Smallest window half-width [s] (an operator cannot start an OB to better than this).
    rounding_warn_fraction : float
        Warn when minute rounding widens an ESO window by more than this fraction of P_b.
    merge_overlaps : bool
        Merge overlapping ESO windows of one target into one OB instead of raising.
    proposal_format : str
        ``ecsv``, ``csv`` or ``latex`` for the proposal table.
    keck_rotmode : str
        Keck ``rotmode=`` value (``vertical`` = parallactic slit, right for spectroscopy).
    force : bool
        Write a format even when the plan's site is not one of its observatory's sites.
    semester : str or None
        Proposal semester ``2041A``/``2041B`` or ESO period ``P147``; None = the one containing
        the plan.
    seeing_arcsec : float
        Seeing limit of the ESO constraint set [arcsec].
    instrument : str or None
        Instrument configuration (``ucbplan instruments``) whose readout mode and overheads go
        into the ESO OB templates; None = the exposure numbers of the plan only.
    eso_templates : str or None
        YAML file naming the ESO p2 acquisition and science templates and their keywords.
    strict : bool
        Refuse (:class:`~ucbplan.observing.exports.queue.ServiceModeError`) instead of noting a
        visit that waits between exposures in a service-mode queue format (``--strict``).
    """

    acquisition_s: float | None = None
    tolerance_sigma: float = 3.0
    tolerance_floor_s: float = 10.0
    rounding_warn_fraction: float = 0.1
    merge_overlaps: bool = False
    proposal_format: str = "ecsv"
    keck_rotmode: str = "vertical"
    force: bool = False
    semester: str | None = None
    seeing_arcsec: float = 1.0
    instrument: str | None = None
    eso_templates: str | None = None
    strict: bool = False

    def __post_init__(self) -> None:
        why = "acquisition before the first exposure; a block must fit in one night"
        if self.acquisition_s is not None:
            check_range("acquisition", self.acquisition_s, 0.0, MAX_BLOCK_S, "s", why)
        why = "window half-width in units of the block's 1-sigma timing error"
        check_range("tolerance_sigma", self.tolerance_sigma, 0.0, MAX_TOLERANCE_SIGMA, "", why)
        why = "smallest window half-width; a day at most"
        check_range("tolerance_floor", self.tolerance_floor_s, 0.0, DAY_S, "s", why)
        check_range("rounding_warn_fraction", self.rounding_warn_fraction, 0.0, 1.0)
        why = "seeing limit of the ESO constraint set"
        check_range("seeing", self.seeing_arcsec, 0.0, 5.0, "arcsec", why, low_open=True)
        if self.semester is not None:
            semester_dates(self.semester)  # refuses anything but 2041A, 2041B, P147
        if not isinstance(self.keck_rotmode, str) or self.keck_rotmode not in KECK_ROTMODES:
            raise InputError(
                f"rotmode: expected {', '.join(KECK_ROTMODES)} (Keck starlist rotator "
                f"modes), got {shorten(self.keck_rotmode, 40)}"
            )


@dataclass(frozen=True, slots=True)
class ExportResult:
    """Bytes to write plus notes for the user (defaults taken, rounding warnings)."""

    content: bytes
    suffix: str
    notes: tuple[str, ...] = field(default_factory=tuple)


#: One export format: ``(blocks table, options) -> ExportResult``.
Exporter = Callable[[Table, ExportOptions], ExportResult]
