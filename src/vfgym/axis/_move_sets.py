"""An axis's move sets: the moves it is tuned on (train) and judged on (test), each a
list of moves or a seeded random distribution (:class:`vfgym.axis.Axis` holds them).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from vfgym._validate import check_choice
from vfgym.moves.distribution import DEFAULT_DISTRIBUTION, MoveDistribution
from vfgym.moves.scenarios import SPLITS, Scenario
from vfgym.params import PAPER_PLANT, Plant


@dataclass(frozen=True)
class MoveSet:
    """The moves of one split: a list of moves, or a seeded random distribution.

    Parameters
    ----------
    moves : tuple of Scenario
        The moves (names unique within the set); give these or ``random``.
    random : MoveDistribution or None
        A distribution; its set is ``count`` draws from ``first_seed``.

    Raises
    ------
    ValueError
        If neither or both are given, a move is not a :class:`vfgym.Scenario`, or two
        moves share a name.
    """

    moves: tuple[Scenario, ...] = ()
    random: MoveDistribution | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "moves", tuple(self.moves))
        if (self.random is None) == (not self.moves):
            raise ValueError(
                f"moves={list(self.moves)!r}, random={self.random!r} is not allowed: give "
                "one or more moves (vfgym.Scenario fields) or random: a MoveDistribution"
            )
        if self.random is not None and not isinstance(self.random, MoveDistribution):
            raise ValueError(f"random={self.random!r} must be a MoveDistribution")
        names = [m.name for m in self.moves]
        for i, m in enumerate(self.moves):
            if not isinstance(m, Scenario):
                raise ValueError(f"moves[{i}]={m!r} must be a vfgym.Scenario")
            if names.index(m.name) != i:
                raise ValueError(
                    f"moves[{i}].name={m.name!r} is not allowed: the name of moves"
                    f"[{names.index(m.name)}] already; give each move its own name"
                )

    def scenarios(self, split: str, base: Plant = PAPER_PLANT) -> list[Scenario]:
        """The set as scenarios.

        Parameters
        ----------
        split : str
            ``train`` or ``test``: the split a distribution draws from.
        base : Plant
            The axis's plant (a distribution's loads are drawn on it).

        Returns
        -------
        list of Scenario
            The listed moves, or the distribution's ``count`` draws of ``split``.
        """
        if self.random is not None:
            return self.random.scenarios(split, base)
        return list(self.moves)

    def pick(self, seed: int, split: str, base: Plant = PAPER_PLANT) -> Scenario:
        """The move of a seed, as the environments draw them.

        Parameters
        ----------
        seed : int
            The scenario seed.
        split : str
            ``train`` or ``test``: the split a distribution draws from.
        base : Plant
            The axis's plant.

        Returns
        -------
        Scenario
            The distribution's draw, or for a list the move ``seed mod len(moves)``
            (seeds cycle through a listed set).
        """
        if self.random is not None:
            return self.random.draw(seed, split, base)
        return self.moves[int(seed) % len(self.moves)]


@dataclass(frozen=True)
class MoveSets:
    """An axis's train moves and test moves.

    Parameters
    ----------
    train : MoveSet
        What a sweep tunes on, the envs' train split (default: 16 draws of the default
        random distribution).
    test : MoveSet
        What ``vfgym evaluate`` judges on by default, the envs' test split (default: 32
        draws).

    Raises
    ------
    ValueError
        If either is not a :class:`MoveSet`.
    """

    train: MoveSet = field(
        default_factory=lambda: MoveSet(random=replace(DEFAULT_DISTRIBUTION, count=16))
    )
    test: MoveSet = field(
        default_factory=lambda: MoveSet(random=replace(DEFAULT_DISTRIBUTION, count=32))
    )

    def __post_init__(self) -> None:
        for split in SPLITS:
            if not isinstance(getattr(self, split), MoveSet):
                raise ValueError(f"{split}={getattr(self, split)!r} must be a MoveSet")

    def of(self, split: str) -> MoveSet:
        """The move set of a split.

        Parameters
        ----------
        split : str
            ``train`` or ``test``.

        Returns
        -------
        MoveSet
            Its moves.
        """
        return getattr(self, check_choice("split", split, SPLITS))
