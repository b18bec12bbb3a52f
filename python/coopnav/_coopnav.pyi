"""Type hints of the compiled module ``coopnav._coopnav`` (re-exported by ``coopnav``)."""

import os
from typing import Any, Dict, List, Literal, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

Kind = Literal["simulate", "plan"]
Settings = Union[str, Mapping[str, Any]]
"""A TOML string or a dict holding the same tables and keys."""
FloatArray = npt.NDArray[np.float64]
Columns = Dict[str, Any]
"""Named numpy columns (and lists of strings): ``pandas.DataFrame(columns)`` takes it directly."""

class Scenario:
    """A closed-loop ("simulate") or pre-deployment ("plan") scenario, checked as the CLI checks it."""

    @staticmethod
    def example(kind: Kind = "simulate") -> Scenario:
        """The embedded example (``coopnav simulate --example`` / ``coopnav plan --example``)."""
    @staticmethod
    def example_toml(kind: Kind = "simulate") -> str:
        """The embedded example's TOML text."""
    @staticmethod
    def load(path: Union[str, os.PathLike[str]], kind: Kind = "simulate", allow_large: bool = False) -> Scenario:
        """Reads a TOML scenario file; ``ValueError`` names the file and the bad field."""
    @staticmethod
    def from_toml(text: str, kind: Kind = "simulate", allow_large: bool = False) -> Scenario:
        """Parses TOML text (messages call it ``<string>``)."""
    @staticmethod
    def from_dict(data: Mapping[str, Any], kind: Kind = "simulate", allow_large: bool = False) -> Scenario:
        """Builds a scenario from a dict of the TOML tables (messages call it ``<dict>``)."""
    @property
    def kind(self) -> Kind: ...
    @property
    def source(self) -> str:
        """The file, or ``<embedded NAME>``, ``<string>``, ``<dict>``."""
    def to_dict(self) -> Dict[str, Any]:
        """Every field, as the TOML file holds it."""
    def to_toml(self) -> str: ...

class Planner:
    """The receding-horizon look-ahead CNA planner (Hudson 2012)."""

    def __init__(self, config: Settings) -> None:
        """From ``coopnav_plan::PlannerConfig``'s fields: look_ahead, motion, penalties (and error,
        cost, limits, search)."""
    @staticmethod
    def from_scenario(scenario: Scenario, policy: str = "planner") -> Planner:
        """The planner a scenario's ``[policy.NAME]`` table configures (``planner``, or
        ``planner-estimator`` with its settings from the mission rule)."""
    @staticmethod
    def from_spec(spec: Settings, platform: Settings) -> Planner:
        """From a ``[policy.planner]`` table (``coopnav_plan::PlannerSpec``: tree, limits, penalty,
        deadline, search, cost of kind ``hudson``) and a ``[platform]`` table (speed, tau,
        max_turn_rate_deg_s, cna), as every scenario file writes them."""
    @property
    def config(self) -> Dict[str, Any]: ...
    def initial_errors(
        self, sigma0: float, eps0: float, cna_position: FloatArray, auv_positions: FloatArray
    ) -> FloatArray:
        """Initial error states (N, 5): sigma2, eps2, line of sight x, y, z."""
    def decide(
        self,
        t: float,
        cna_pose: FloatArray,
        errors: FloatArray,
        forecast: FloatArray,
        estimates: Optional[FloatArray] = None,
        cna_variance: float = 0.0,
    ) -> Dict[str, Any]:
        """One decision from ``cna_pose`` [x, y, z, heading_rad(, pitch_rad)], ``errors`` (N, 5) and
        ``forecast`` (N, levels, 3), the AUV positions at t + tau, t + 2 tau, ...; ``estimates``
        (N, 4: p_ee, p_en, p_nn, process_noise) for the estimator-aware cost; ``cna_variance``
        (m² per horizontal axis, >= 0) is the CNA's own position variance, added to each ping's
        range variance by that cost (0: the term is off).

        Returns ``heading``, ``pitch`` (rad) and ``next`` (x, y, z) of the next waypoint, ``cost``,
        ``levels_searched``, ``levels_requested``, ``option``, ``nodes``, ``turn``, ``pitch_change``.
        """

def plan(scenario: Scenario) -> Dict[str, Any]:
    """The whole pre-deployment plan (``coopnav plan``): ``steps`` and ``decisions`` (numpy
    columns; per-AUV columns have shape (steps, N)), ``names`` and ``summary``."""

class _FilterReadout:
    """What both filter classes expose (a typing-only base: at run time each class has these
    properties itself)."""

    @property
    def t(self) -> float: ...
    @property
    def state(self) -> FloatArray: ...
    @property
    def covariance(self) -> FloatArray: ...

class AuvEkf(_FilterReadout):
    """The survey AUV's OWTT filter: state [E, N, speed, heading, compass bias]."""

    def __init__(
        self, t0: float, e: float, n: float, speed: float, heading: float, params: Optional[Settings] = None
    ) -> None: ...
    def predict(self, t: float, yaw_rate: float = 0.0) -> bool: ...
    def update_speed(self, speed: float) -> str:
        """Returns "applied", "gated" or "unusable"."""
    def update_heading(self, heading: float) -> str: ...
    def update_range(
        self,
        range: float,
        travel_time: float,
        transponder: Sequence[float],
        auv_depth: Optional[float] = None,
        transponder_sd: float = 0.0,
    ) -> str: ...

class SurfaceEkf(_FilterReadout):
    """A surface vehicle's filter: state [E, N, speed, heading]."""

    def __init__(
        self, t0: float, e: float, n: float, speed: float, heading: float, params: Union[None, str, Settings] = None
    ) -> None:
        """``params``: "ship" (default), "buoy" or every SurfaceParams field."""
    def predict(self, t: float) -> None: ...
    def update(self, kind: Literal["east", "north", "speed", "heading"], value: float) -> str: ...

def postprocess(log: Union[str, os.PathLike[str], Mapping[str, Sequence[Any]]], config: Optional[Settings] = None) -> Dict[str, Any]:
    """EKF + RTS smoother over a logged mission (``coopnav hbl postprocess``): ``samples``
    (estimates.csv's columns), ``residuals`` and ``summary``."""

class TransmissionLoss:
    """A transmission-loss model, dB re 1 m."""

    @staticmethod
    def analytic(k: float = 1.5, freq_hz: float = 25000.0) -> TransmissionLoss: ...
    @staticmethod
    def bellhop(bathymetry: Optional[Union[str, os.PathLike[str]]] = None) -> TransmissionLoss:
        """The real BELLHOP; ``ValueError`` when it is not installed."""
    def cached(self, anchor: Sequence[float], grid: Settings) -> TransmissionLoss:
        """A cached grid of this model (grid: bearings, range_step, max_range, depth_step, max_depth)."""
    def between(self, source: Sequence[float], receivers: FloatArray) -> FloatArray:
        """TL from ``source`` (x, y, depth) to each row of ``receivers`` (M, 3)."""
    def field(self, source: Sequence[float], bearing_deg: float, ranges: FloatArray, depths: FloatArray) -> FloatArray:
        """TL along a radial: shape (len(depths), len(ranges))."""

def p_success(rate: int, tl_db: FloatArray, noise_db: float = 0.0, model: Optional[Settings] = None) -> FloatArray: ...
def simulate(scenario: Scenario, policy: str = "planner-estimator", seed: Optional[int] = None) -> Dict[str, Any]:
    """One closed-loop mission: ``timeseries``, ``comms``, ``cna`` (numpy columns) and ``summary``."""
def monte_carlo(
    scenario: Scenario, policies: List[str], runs: int, seed: Optional[int] = None, allow_large: bool = False
) -> Dict[str, Any]:
    """Seeded Monte Carlo comparison of policies: the CLI's ``--json`` content plus ``table``."""
