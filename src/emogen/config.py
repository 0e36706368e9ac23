"""Configuration: pydantic models (frozen, unknown keys rejected), loaded from TOML.

Defaults are the paper's (Sections III-B, III-C and IV-A). A typo or an out-of-range value is
a :class:`~emogen.errors.ConfigError` that names the key::

    invalid config ga.toml: unknown key 'mutaton_genes'
    invalid config sim.toml: 'ga.mutation_genes' must be >= 0; got -1
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from types import UnionType
from typing import Annotated, Any, Literal, TypeVar, Union, get_args, get_origin

import pydantic
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator
from pydantic.fields import FieldInfo
from pydantic_core import PydanticCustomError

from emogen.errors import ConfigError

#: Selections per generation in the paper's simulations (Section IV-A): two at initialisation
#: (g = 0), four in generations 1-5, five in 6-10.
PAPER_SELECTIONS: tuple[int, ...] = (2, 4, 4, 4, 4, 4, 5, 5, 5, 5, 5)
PROTOCOL_EMOTIONS: tuple[str, ...] = ("happy", "sad", "angry", "fearful")


class _Strict(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")

    @model_validator(mode="before")
    @classmethod
    def _no_quoted_numbers(cls, data: Any) -> Any:
        """A number or true/false written in quotes (``generations = "10"``) is refused, naming
        the key: pydantic would take the text, and a typo in it would go unnoticed."""
        if isinstance(data, dict):
            quoted = [
                (key, value)
                for key, value in data.items()
                if isinstance(value, str)
                and _reads_as_number(value)
                and key in cls.model_fields
                and _numbers_only(cls.model_fields[key].annotation)
            ]
            if quoted:
                raise ValidationError.from_exception_data(
                    cls.__name__,
                    [
                        {
                            "type": PydanticCustomError(
                                "quoted",
                                "is text in quotes: write numbers and true/false without "
                                "them ({key} = {value})",
                                {"key": key, "value": value},
                            ),
                            "loc": (key,),
                            "input": value,
                        }
                        for key, value in quoted
                    ],
                )
        return data


def _reads_as_number(text: str) -> bool:
    """Whether pydantic would take ``text`` as a number or a boolean."""
    if text.strip().lower() in ("true", "false", "yes", "no", "on", "off"):
        return True
    try:
        float(text)
    except ValueError:
        return False
    return True


def _numbers_only(annotation: Any) -> bool:
    """Whether a field takes numbers or booleans only (with None): not text, not a Literal."""
    kinds, stack = set(), [annotation]
    while stack:
        a = stack.pop()
        if get_origin(a) in (Union, UnionType, Annotated):
            stack += [x for x in get_args(a) if not isinstance(x, FieldInfo)]
            continue
        kinds.add(a)
    kinds.discard(type(None))
    return bool(kinds) and kinds <= {int, float, bool}


class InitConfig(_Strict):
    """How generation 0 is made (Section III-C)."""

    kind: Literal["protocol", "fixed"] = "protocol"
    #: Unique core shapes active per protocol-generated face, drawn from U{lo..hi} (Table IV).
    activation_range: tuple[Annotated[int, Field(ge=1)], Annotated[int, Field(ge=1)]] = (3, 8)
    #: Protocol: the emotions with building-block faces, and how many faces each.
    emotions: tuple[str, ...] = PROTOCOL_EMOTIONS
    faces_per_emotion: Annotated[int, Field(ge=0)] = 2
    #: Fixed: a TOML file of sets (None: the packaged sample ``emogen/data/fixed_init.toml``).
    fixed_file: Path | None = None
    #: Fixed: which set, numbered from 1 (None: drawn at random at every initialisation).
    fixed_option: Annotated[int, Field(ge=1)] | None = None
    #: On reset: draw a new initial population, or show the first one again.
    on_reset: Literal["reinitialise", "keep"] = "reinitialise"

    @model_validator(mode="after")
    def _range_ordered(self) -> InitConfig:
        lo, hi = self.activation_range
        if lo > hi:
            raise ValueError(f"activation_range must be [lo, hi] with lo <= hi; got [{lo}, {hi}]")
        return self


class GAConfig(_Strict):
    """The genetic algorithm (Section III-B, Algorithm 1) and the study's options (III-C)."""

    population_size: Annotated[int, Field(ge=2, le=100)] = 10
    #: Diversity boost: fresh random faces R(x) in the last slots of every new population.
    random_faces: Annotated[int, Field(ge=0)] = 4
    #: m, genes mutated per crossover child.
    mutation_genes: Annotated[int, Field(ge=0)] = 2
    #: x, genes drawn for a random face.
    random_genes: Annotated[int, Field(ge=1)] = 6
    #: G: the participant selects in generations 0..G; the result is generation G's elite.
    generations: Annotated[int, Field(ge=0, le=1000)] = 10
    min_selections: Annotated[int, Field(ge=1)] = 1
    #: Default: the population size (10, "unconstrained").
    max_selections: Annotated[int, Field(ge=1)] = 10
    eye_motion: bool = True
    identity: str = "generic"
    #: "emogen" (Algorithm 1) or "classical" (fitness-ranked pairs, two children per pair).
    variant: Literal["emogen", "classical"] = "emogen"
    init: InitConfig = InitConfig()

    @model_validator(mode="before")
    @classmethod
    def _default_max_selections(cls, data: Any) -> Any:
        if isinstance(data, dict) and "max_selections" not in data:
            size = data.get("population_size", 10)
            if isinstance(size, int) and not isinstance(size, bool):
                return {**data, "max_selections": size}
        return data

    @model_validator(mode="after")
    def _consistent(self) -> GAConfig:
        n = self.population_size
        if self.random_faces > n - 1:
            raise ValueError(
                f"random_faces must leave room for the elite (at most population_size - 1 = "
                f"{n - 1}); got {self.random_faces}"
            )
        if self.max_selections > n:
            raise ValueError(
                f"max_selections must be at most population_size ({n}); got {self.max_selections}"
            )
        if self.min_selections > self.max_selections:
            raise ValueError(
                f"min_selections ({self.min_selections}) must not exceed max_selections "
                f"({self.max_selections})"
            )
        if self.init.kind == "protocol":
            emotional = len(self.init.emotions) * self.init.faces_per_emotion
            if emotional + 1 > n:
                raise ValueError(
                    f"protocol initialisation needs population_size >= {emotional + 1} "
                    f"({len(self.init.emotions)} emotions × {self.init.faces_per_emotion} "
                    f"faces + the neutral); got {n}"
                )
        return self

    def arbitrary_faces(self) -> int:
        """Protocol initialisation: faces from all genes (the rest are emotions + neutral)."""
        return self.population_size - len(self.init.emotions) * self.init.faces_per_emotion - 1


#: The observers' similarity metrics (Section IV-B): ED on unique core genes (eq. 11), CD on
#: full weight vectors (eq. 12), vertex RMS (eq. 13), ED and standardised ED in PCA space
#: (eqs. 14-15) and the vertex-space Mahalanobis distance (eq. 16).
MetricName = Literal["cd", "ed", "vertex_rms", "pca_ed", "std_ed", "mahalanobis"]
EMPIRICAL_METRICS: tuple[str, ...] = ("pca_ed", "std_ed", "mahalanobis")


class MetricConfig(_Strict):
    """The similarity metric a simulated observer selects by. In TOML, ``metric = "ed"`` is
    short for ``[metric] name = "ed"``."""

    name: MetricName = "cd"
    #: Empirical metrics: training faces, a Parquet or CSV table with one column per shape (or
    #: gene) name; other columns are ignored.
    training: Path | None = None
    #: Empirical metrics: a pandas query selecting the training rows (e.g. "rank == 0").
    query: str | None = None
    #: Empirical metrics: the PCA keeps the components explaining this fraction of variance.
    variance: Annotated[float, Field(gt=0, le=1)] = 0.99
    #: Mahalanobis: ridge λ = ridge · tr(S) / 3N added to the training covariance.
    ridge: Annotated[float, Field(gt=0)] = 1.0
    #: Vertex RMS: rotate the eyeballs with the gaze weights, as the model renders them.
    gaze: bool = True

    @model_validator(mode="before")
    @classmethod
    def _from_name(cls, data: Any) -> Any:
        return {"name": data} if isinstance(data, str) else data

    @model_validator(mode="after")
    def _training_needed(self) -> MetricConfig:
        if self.name in EMPIRICAL_METRICS and self.training is None:
            raise ValueError(
                f"metric '{self.name}' is empirical: give metric.training, a Parquet or CSV "
                "table of training faces (one column per shape name)"
            )
        return self


Unit = Annotated[float, Field(ge=0, le=1)]


class DynamicSimulationConfig(_Strict):
    """Dynamic faces (docs/ga.md, "Simulated observers of dynamic faces"): a moving target."""

    clip_s: Annotated[float, Field(ge=0.2, le=10)] = 1.25
    hold_s: Annotated[float, Field(ge=0, le=10)] = 0.75
    min_segment_s: Annotated[float, Field(gt=0)] = 0.08
    #: Times sampled evenly over the clip for the trajectory metric (26: every 50 ms of 1.25 s).
    samples: Annotated[int, Field(ge=2, le=500)] = 26
    #: Per gene of the target: [onset, acceleration, peak, deceleration, offset] in [0, 1].
    timing: dict[str, Annotated[list[Unit], Field(min_length=5, max_length=5)]] = {}
    #: Evolve the amplitudes only, every gene's timing held at the target's.
    hold_timing: bool = False


class SimulationConfig(_Strict):
    """A simulated study: an observer selects by a metric toward a target (Section IV-A)."""

    ga: GAConfig = GAConfig()
    #: Target face: {gene or shape name: weight}. Or give target_file instead.
    target: (
        Annotated[dict[str, Annotated[float, Field(ge=0, le=1)]], Field(min_length=1)] | None
    ) = None
    #: Target face from a table (Parquet or CSV, one column per shape or gene name): a weight
    #: file, a dataset, or a simulation's faces table written with all weights.
    target_file: Path | None = None
    #: Which row of target_file (numbered from 0); may be omitted when it has one row.
    target_row: Annotated[int, Field(ge=0)] | None = None
    runs: Annotated[int, Field(ge=1)] = 500
    seed: Annotated[int, Field(ge=0, lt=2**63)] | None = None
    #: Faces selected in generation g = 0, 1, ...; the last value repeats beyond the list.
    #: Ignored by the classical variant, whose observer ranks the whole population.
    selections: tuple[Annotated[int, Field(ge=1)], ...] = Field(
        default=PAPER_SELECTIONS, min_length=1
    )
    metric: MetricConfig = MetricConfig()
    #: Choice noise: 0 selects the closest faces; T > 0 draws them by a softmax of −distance/T
    #: (in the metric's units), without replacement, to model real participants.
    noise_temperature: Annotated[float, Field(ge=0)] = 0.0
    #: Apply the model's corrections (correctives, collisions) to every shown face.
    correct: bool = False
    #: Dynamic faces: the target moves and the GA evolves time courses (None: static faces).
    dynamic: DynamicSimulationConfig | None = None

    @model_validator(mode="after")
    def _consistent(self) -> SimulationConfig:
        if self.target is None and self.target_file is None:
            raise ValueError("'target' is required (or give target_file)")
        if self.target is not None and self.target_file is not None:
            raise ValueError("give either target or target_file, not both")
        if self.target is not None and not any(v > 0 for v in self.target.values()):
            raise ValueError("target must have at least one non-zero weight")
        if self.target_row is not None and self.target_file is None:
            raise ValueError("target_row needs target_file")
        ga = self.ga
        if ga.variant == "classical":
            if ga.max_selections < ga.population_size:
                raise ValueError(
                    "the classical variant ranks the whole population: ga.max_selections must "
                    f"be population_size ({ga.population_size}); got {ga.max_selections}"
                )
            return self
        bad = [s for s in self.selections if not ga.min_selections <= s <= ga.max_selections]
        if bad:
            raise ValueError(
                f"selections must lie within [ga.min_selections, ga.max_selections] = "
                f"[{ga.min_selections}, {ga.max_selections}]; got {bad}"
            )
        return self

    def selections_at(self, generation: int) -> int:
        return self.selections[min(generation, len(self.selections) - 1)]

    @pydantic.model_serializer(mode="wrap")
    def _static_as_before(self, handler: pydantic.SerializerFunctionWrapHandler) -> dict[str, Any]:
        """A static simulation serialises as before dynamic faces: no ``dynamic`` key."""
        data: dict[str, Any] = handler(self)
        if self.dynamic is None:
            data.pop("dynamic", None)
        return data


M = TypeVar("M", bound=BaseModel)


#: What a TOML writer reads instead of pydantic's words ("Input should be a valid tuple").
_PLAIN = {
    "tuple_type": 'must be a list in square brackets, e.g. ["a", "b"]',
    "list_type": 'must be a list in square brackets, e.g. ["a", "b"]',
    "int_parsing": "must be a whole number",
    "int_type": "must be a whole number",
    "int_from_float": "must be a whole number",
    "float_parsing": "must be a number",
    "float_type": "must be a number",
    "string_type": 'must be text in quotes, e.g. "abc"',
    "bool_parsing": "must be true or false",
    "bool_type": "must be true or false",
    "dict_type": "must be a table of keys",
    "model_type": "must be a table of keys",
    "missing": "is required",
}


def plain_words(err: Any) -> str | None:
    """One pydantic error in a researcher's words (None: pydantic's own message will do)."""
    ctx = err.get("ctx") or {}
    if err["type"] == "too_short":
        n = int(ctx.get("min_length", 1))
        return f"must have at least {n} entr{'y' if n == 1 else 'ies'}"
    if err["type"] == "too_long":
        n = int(ctx.get("max_length", 0))
        return f"must have at most {n} entr{'y' if n == 1 else 'ies'}"
    return _PLAIN.get(err["type"])


def key_path(loc: Any) -> str:
    """A pydantic error's location as the config file reads: ``blocks[3].points`` (list entries
    counted from 1)."""
    out = ""
    for p in loc:
        out += f"[{p + 1}]" if isinstance(p, int) else ("." if out else "") + str(p)
    return out


def format_validation_error(exc: ValidationError, source: str) -> str:
    """One line naming every bad key: ``unknown key 'x'``, ``'ga.generations' must be …``."""
    parts = []
    for err in exc.errors():
        loc = [str(p) for p in err["loc"]]
        if err["type"] == "extra_forbidden":
            where = f" in [{key_path(err['loc'][:-1])}]" if len(loc) > 1 else ""
            parts.append(f"unknown key '{loc[-1]}'{where}")
            continue
        msg = plain_words(err) or err["msg"].removeprefix("Value error, ")
        msg = msg.replace("Input should be", "must be").replace("greater than or equal to", ">=")
        msg = msg.replace("less than or equal to", "<=").replace("greater than", ">")
        msg = msg.replace("less than", "<")
        if loc and msg.startswith(f"{loc[-1]} must "):  # "name must be …" under 'name'
            msg = msg[len(loc[-1]) + 1 :]
        said = "got " in msg or err["type"] == "quoted"  # the message names the value itself
        if loc:
            parts.append(
                f"'{key_path(err['loc'])}' {msg}" + ("" if said else f"; got {err.get('input')!r}")
            )
        else:
            parts.append(msg)
    return f"invalid config {source}: " + "; ".join(parts)


def validate_config(model: type[M], data: dict[str, Any], source: str = "(arguments)") -> M:
    """``model.model_validate(data)`` with a ConfigError naming each bad key."""
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(format_validation_error(exc, source)) from None


def read_toml(path: Path) -> dict[str, Any]:
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise ConfigError(f"cannot read config file {path}: {exc.strerror}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config {path} is not valid TOML: {exc}") from None


def load_config(model: type[M], path: Path) -> M:
    """A config model from a TOML file, e.g. ``load_config(GAConfig, Path("ga.toml"))``."""
    return validate_config(model, read_toml(path), str(path))


def merge(base: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Nested dict update (overrides win); used to apply command-line options to a TOML."""
    out = dict(base)
    for key, value in overrides.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = value
    return out
