"""An axis: one machine (its plant and measures), the moves it is tuned on (train) and
judged on (test), and what it does not know exactly (its uncertainty): vfgym's problem
object. Every tuner, env, scheduler and evaluation holds one; :data:`PAPER_AXIS` is the
default, and :mod:`vfgym.axis._file` reads and writes one as a YAML file.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from vfgym.axis._checks import check_arrives, check_limit, check_measures
from vfgym.axis._move_sets import MoveSet, MoveSets
from vfgym.axis._uncertainty import EXACT, PlantVariant, Uncertainty, plant_design
from vfgym.moves.distribution import LOAD_DISTRIBUTION
from vfgym.moves.scenarios import SCENARIOS, SPLITS, Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, Measures, Plant


def _listed(axis: Axis) -> dict[str, Scenario]:  # (Axis: a forward reference)
    """The axis's listed moves by key path (``moves.train[0]``)."""
    return {
        f"moves.{split}[{i}]": sc
        for split in SPLITS
        for i, sc in enumerate(axis.moves.of(split).moves)
    }


@dataclass(frozen=True)
class Axis:
    """One machine and its moves: the plant (with its load), the measures' windows, and
    the train and test move sets. The default is the paper's axis: the paper's plant,
    its load fixed, with 16 train and 32 test moves of the default random distribution
    (:data:`~vfgym.moves.distribution.DEFAULT_DISTRIBUTION`: distance, direction and profile
    vary); what ``vfgym`` uses without ``--axis``; ``experiments/axes/paper.yaml``.

    Every listed move must be able to arrive: its duration exceeds its ideal move time on
    the axis (:func:`vfgym.moves.scenarios.ideal_move_time_s`) and its command reaches
    its target within it.

    Parameters
    ----------
    name : str
        The axis's name (an axis file's default: its stem).
    description : str
        Free text.
    plant : Plant
        The machine: motor (with its load), servo, controller clock.
    measures : Measures
        The measures' windows and bands on this machine.
    moves : MoveSets
        The train and test move sets; a move's load is added to the plant's.
    uncertainty : Uncertainty
        What the plant's figures do not state exactly (:mod:`vfgym.axis`):
        tuners stay feasible on every plant of its design, verdicts are judged across
        plants drawn within it. Default: exactly known.

    Raises
    ------
    ValueError
        If a field has the wrong type, or a listed move cannot arrive within its duration.
    """

    name: str = "paper"
    description: str = ""
    plant: Plant = PAPER_PLANT
    measures: Measures = DEFAULT_MEASURES
    moves: MoveSets = field(default_factory=MoveSets)
    uncertainty: Uncertainty = EXACT

    def __post_init__(self) -> None:
        for key, kind in (
            ("plant", Plant),
            ("measures", Measures),
            ("moves", MoveSets),
            ("uncertainty", Uncertainty),
        ):
            if not isinstance(getattr(self, key), kind):
                raise ValueError(f"{key}={getattr(self, key)!r} must be a vfgym {kind.__name__}")
        self.uncertainty.check_plant(self.plant)
        check_limit(self.plant)  # first: a units slip would read as moves too short
        listed = _listed(self)
        for key, sc in listed.items():
            check_arrives(sc, self.plant, key)
        drawn = {
            f"moves.{split}.random": ms.random
            for split in SPLITS
            if (ms := self.moves.of(split)).random is not None
        }
        check_measures(self.measures, self.plant, listed, drawn)

    def design_plants(self) -> tuple[PlantVariant, ...]:
        """The true plants a tuner must stay feasible on: the corners of the axis's
        uncertainty and points drawn inside (:func:`vfgym.axis.plant_design`);
        none where it is exactly known.

        Returns
        -------
        tuple of PlantVariant
            The design's plants, relative to the modelled one.
        """
        return plant_design(self.uncertainty, self.plant)

    def scenarios(self, split: str) -> list[Scenario]:
        """The train or test moves.

        Parameters
        ----------
        split : str
            ``train`` or ``test``.

        Returns
        -------
        list of Scenario
            The split's move set, drawn on the axis's plant if random.
        """
        return self.moves.of(split).scenarios(split, self.plant)

    def scenario(self, name: str | Scenario) -> Scenario:
        """A move by name.

        Parameters
        ----------
        name : str or Scenario
            A listed move of the axis, a named scenario (:data:`vfgym.SCENARIOS`), or
            ``<split>-<seed>`` of a random move set; a Scenario is returned as it is.

        Returns
        -------
        Scenario
            The move.

        Raises
        ------
        ValueError
            If the name is none of these.
        """
        if isinstance(name, Scenario):
            return name
        for split in SPLITS:
            for sc in self.moves.of(split).moves:
                if sc.name == name:
                    return sc
        if name in SCENARIOS:
            return SCENARIOS[name]
        split, _, seed = str(name).partition("-")
        if split in SPLITS and seed.isdigit() and self.moves.of(split).random is not None:
            return self.moves.of(split).pick(int(seed), split, self.plant)
        listed = [sc.name for s in SPLITS for sc in self.moves.of(s).moves]
        raise ValueError(
            f"scenario={name!r} is not known on axis {self.name!r}: choose one of "
            f"{', '.join(listed + list(SCENARIOS))}"
            + (
                ", or <split>-<seed> of a random move set"
                if any(self.moves.of(s).random is not None for s in SPLITS)
                else ""
            )
        )

    def scenario_set(self, spec: str | Scenario | list | tuple) -> list[Scenario]:
        """Scenarios from a spec, resolved on the axis.

        Parameters
        ----------
        spec : str, Scenario, list or tuple
            ``train`` / ``test`` (the axis's move sets), ``named`` (the eight named
            scenarios), a move's name (:meth:`scenario`), a comma-separated list, or a
            list of these.

        Returns
        -------
        list of Scenario
            The scenarios, in order.
        """
        if isinstance(spec, Scenario):
            return [spec]
        if isinstance(spec, (list, tuple)):
            return [s for item in spec for s in self.scenario_set(item)]
        spec = str(spec)
        if "," in spec:
            return self.scenario_set([p.strip() for p in spec.split(",") if p.strip()])
        if spec in SPLITS:
            return self.scenarios(spec)
        if spec == "named":
            return list(SCENARIOS.values())
        return [self.scenario(spec)]


PAPER_AXIS = Axis()
"""The paper's axis, the default problem: ``experiments/axes/paper.yaml`` holds the same."""

LOADS_AXIS = Axis(
    name="loads",
    description="the paper's plant under a random load per move (the agents' distribution)",
    moves=MoveSets(
        train=MoveSet(random=replace(LOAD_DISTRIBUTION, count=16)),
        test=MoveSet(random=replace(LOAD_DISTRIBUTION, count=32)),
    ),
)
"""The paper's plant under a random load per move (:data:`vfgym.moves.LOAD_DISTRIBUTION`):
the distribution the agents learn across, the environments' default axis;
``experiments/axes/loads.yaml`` holds the same."""
