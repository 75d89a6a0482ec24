"""Noun phrases and clauses of a canonical prompt (``editing.parse.text``), found on its tokens.

* :func:`chunk_np` -- where a noun phrase that starts at a token ends. Its head is a noun of the grounding
  lexicon (or a garment, place or extra asset noun); before the head come determiners, counts, colours and
  other modifiers ("all crossing pedestrians", "a black and white police car"); after it, in ``target``
  mode, the modifiers that tell objects apart stay with it -- prepositional phrases ("in the red shirt",
  "on the left", "between the bus and the truck"), participles ("crossing the street", "parked by the
  curb", "not moving"), relative clauses ("that is turning left") and adverbs ("ahead"). ``asset`` mode keeps only
  appearance ("a pedestrian in a red coat"); a participle after an asset is its behaviour.
* :func:`split_clauses` -- the prompt's clauses: a hard break (``;``, ``.``, "then", "after that") always
  ends one; ``and`` / ``,`` / "but" only when a new clause starts after it (a verb, a subject with a verb
  or a modal, an unknown verb before a determiner): "remove the white van and make the red car stop" is
  two clauses, "the car between the bus and the truck" one.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Sequence

from simsplat_core.editing.parse import lexicon as lex
from simsplat_core.language.grounding.parse import COLOR_SYNONYMS, NOUNS

PUNCT = frozenset({",", ";", ".", "!", "?", ":"})
#: Prepositions that attach a phrase to the noun before them ("the van *on* the left").
NP_PREPOSITIONS: tuple[str, ...] = (
    "in front of", "in back of", "ahead of", "to the left of", "to the right of", "left of", "right of", "next to",
    "close to", "closest to", "nearest to", "across from", "dressed in", "on top of", "in the middle of",
    "in", "on", "at", "near", "by", "with", "wearing", "from", "of", "beside", "behind", "outside", "inside",
    "along", "under", "carrying", "holding", "without", "between", "among", "around", "past", "beyond", "across",
    "opposite", "towards", "toward", "alongside", "into", "onto", "after", "before", "to", "over", "for",
    "until", "till",
)
#: Prepositions a noun phrase keeps in ``asset`` mode (appearance only).
APPEARANCE_PREPOSITIONS: tuple[str, ...] = ("dressed in", "in", "with", "wearing", "carrying", "holding", "of")
#: Words that may follow a noun and still describe it ("the bus *ahead*").
POST_ADVERBS: tuple[str, ...] = (
    "ahead", "in front", "behind", "nearby", "over there", "there", "here", "closest", "nearest", "furthest",
    "farthest", "first", "last", "up ahead", "down the road", "further ahead", "in the distance",
)
#: ``-ing`` words that are nouns, not participles.
ING_NOUNS = frozenset({"thing", "something", "anything", "nothing", "building", "ring", "king", "string", "ceiling",
                       "evening", "morning", "parking", "clothing", "railing"})
#: Past participles (and -ing words) that describe an object ("the car *parked* by the curb"); one string,
#: so that no literal spells a motion-class name (``scenario/vocabulary.py`` owns those).
ED_PARTICIPLES = frozenset("parked stopped halted stalled abandoned double-parked stationed positioned located placed "
                           "seated queued queueing queuing dressed standing sitting waiting idling".split())
RELATIVES = ("that is", "that are", "which is", "which are", "who is", "who are", "that", "which", "who")
#: A direction after an ``-ing`` word: it is a participle ("the pedestrian crossing *from the left*").
_DIRECTION = re.compile(r"(?:from (?:the )?(?:left|right)|(?:left|right) to"
                        r"|(?:to|towards|toward) the (?:left|right))\b")
#: Where an ``-ing`` word's action happens, when that place is a crosswalk or the road itself: a participle ("a
#: pedestrian crossing *at the crosswalk*" is a person; a crosswalk is not at a crosswalk).
_WHERE_CROSSED = re.compile(r"(?:at|on|over|across|along|in) (?:the |a )?(?:crosswalk|zebra|road|street)\b")
#: A describing clause ends where the clause's own verb's complement starts: a result ("bring the car turning
#: *to a halt*"), a change of speed ("make the car which is going straight *10 km/h faster*", "*twice as fast*")
#: or where to stop ("stop the car which is going straight *before it reaches* the crosswalk").
_VERB_COMPLEMENT = re.compile(
    r"(?:to an? (?:complete |full |dead |gentle |smooth |sudden |quick )?(?:stop|halt|standstill)"
    r"|\d+(?:\.\d+)? (?:km/h|m/s|mph|%) (?:faster|slower|quicker|more|less)"
    r"|(?:twice|thrice|half|\S+ times) (?:as|faster|slower|quicker|the speed)"
    r"|(?:before|until|till) (?:it |they |he |she )?(?:reaches|reaching|gets to|getting to|arrives at|arriving at"
    r"|enters|entering|hits))\b")
COORDINATOR_STARTS = ("the", "a", "an", "all", "every", "each", "node", "object", "this", "that", "those", "these",
                      "both", "another", "any", "it", "them")


@functools.lru_cache(maxsize=64)
def _phrases(words: tuple[str, ...]) -> tuple[tuple[str, ...], ...]:
    return tuple(sorted((tuple(w.split()) for w in words), key=len, reverse=True))


def match(tokens: Sequence[str], i: int, words: Iterable[str]) -> int:
    """Number of tokens of the longest phrase of ``words`` that starts at ``tokens[i]`` (0: none)."""
    for phrase in _phrases(tuple(words)):
        if tuple(tokens[i : i + len(phrase)]) == phrase:
            return len(phrase)
    return 0


def head_noun(tokens: Sequence[str], i: int) -> int:
    """Tokens of the (longest) head noun at ``i`` (0: none)."""
    for n in range(min(lex.HEAD_NOUN_MAX_WORDS, len(tokens) - i), 0, -1):
        if " ".join(tokens[i : i + n]) in lex.HEAD_NOUNS:
            rest = " ".join(tokens[i + n :])
            if (n > 1 and tokens[i + n - 1].endswith("ing") and i + n < len(tokens)
                    and (tokens[i + n] in COORDINATOR_STARTS or _DIRECTION.match(rest) or _WHERE_CROSSED.match(rest))):
                continue  # "the pedestrian crossing the street / from left to right / at the crosswalk": a
                # participle, not a crosswalk
            return n
    return 0


def is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def is_quantity(tokens: Sequence[str], i: int) -> bool:
    """A number followed by a unit ("2 m", "20 km/h"), a coordinate or a count before a unit-less word."""
    return i < len(tokens) and (tokens[i].startswith("@pos") or is_number(tokens[i]) and i + 1 < len(tokens)
                                and tokens[i + 1] in ("m", "s", "km/h", "m/s", "mph", "%", "deg"))


def is_participle(token: str) -> bool:
    return token in ED_PARTICIPLES or (token.endswith("ing") and len(token) > 4 and token not in ING_NOUNS)


def _predicate_start(tokens: Sequence[str], i: int) -> bool:
    """A verb, modal or adverb that starts a predicate at ``i``."""
    if i >= len(tokens):
        return False
    t = tokens[i]
    if t == "stop" and i + 1 < len(tokens) and tokens[i + 1] in ("sign", "signs", "line"):
        return False
    return t in lex.PREDICATE_VERBS or match(tokens, i, lex.MODALS) > 0


def chunk_np(tokens: Sequence[str], i: int, mode: str = "target", exclude: Iterable[str] = ()) -> int:  # noqa: C901 -- noun-phrase grammar: one branch per construction, in precedence order
    """End (exclusive) of the noun phrase starting at ``tokens[i]``; ``i`` when there is none.

    Args:
        mode: ``"target"`` (keeps every describing modifier), ``"anchor"`` (prepositional phrases and adverbs,
            no participle or relative clause: ``editing.parse.anchor`` reads whose those are), ``"asset"`` (appearance
            only) or ``"inner"`` (the object of a preposition: head and pre-modifiers only).
        exclude: prepositions that must not attach to the phrase (a verb's complements: "stop the van
            *before* the intersection").
    """
    n = len(tokens)
    if i >= n or tokens[i] in PUNCT:
        return i
    k = match(tokens, i, lex.PRONOUNS)
    if k and not (k == 1 and tokens[i] in ("those", "these") and i + 1 < n and tokens[i + 1] not in PUNCT
                  and not _predicate_start(tokens, i + 1)):
        return i + k
    if tokens[i] == "node" and i + 1 < n:
        j = i + 2 if tokens[i + 1] in ("id", "number", "no") else i + 1
        return j + 1 if j < n and tokens[j].isdigit() else i
    if tokens[i] in ("object", "obj") and i + 1 < n:
        j = i + 2 if tokens[i + 1] == "id" else i + 1
        return j + 1 if j < n and any(c.isdigit() for c in tokens[j]) else i
    k = match(tokens, i, lex.EGO_WORDS)
    if k and (tokens[i] in ("us", "me") or not head_noun(tokens, i + k)):  # "the ego lane" is a lane; "us back up"
        return i + k
    j = i
    while True:  # determiners and counts
        k = max(match(tokens, j, lex.DETERMINERS), match(tokens, j, lex.QUANTITY_PHRASES))
        if not k and j < n and (is_number(tokens[j]) and not is_quantity(tokens, j)):
            k = 1
        if not k:
            break
        j += k
    head = False
    start = j
    while j < n:  # modifiers, then the head noun (and object nouns compounded with it)
        t = tokens[j]
        k = head_noun(tokens, j)
        if k and not (head and tokens[j] in ("left", "right", "front", "back", "one")):  # "turn the car *left*"
            j += k
            head = True
            continue
        if head or t in PUNCT or is_quantity(tokens, j) or t.startswith("@pos"):
            break
        if t == "and" and j + 1 < n and (tokens[j + 1] in COLOR_SYNONYMS) and j > start:
            j += 1
            continue
        prep = match(tokens, j, NP_PREPOSITIONS) > 0 and not head_noun(tokens, j + 1)  # "the *opposite* lane"
        if j > start and (_predicate_start(tokens, j) or prep):
            break
        if j == start and (prep or t in lex.MODALS or t in ("and", "then")
                           or (j == i and _predicate_start(tokens, j))):  # "to *walk* across": a verb
            break
        j += 1
    if j == i or mode == "inner":
        return j
    return _post_modifiers(tokens, j, mode, frozenset(exclude))


def post_modifiers_end(tokens: Sequence[str], j: int, exclude: Iterable[str] = ()) -> int:
    """End of the phrases from ``tokens[j]`` on that still describe the noun before them (target mode: "in the
    crosswalk", "crossing the street", "that is parked"), prepositions in ``exclude`` not taken."""
    return _post_modifiers(tokens, j, "target", frozenset(exclude))


def _post_modifiers(tokens: Sequence[str], j: int, mode: str, exclude: frozenset[str]) -> int:
    n = len(tokens)
    preps = APPEARANCE_PREPOSITIONS if mode == "asset" else NP_PREPOSITIONS
    while j < n:
        if mode != "asset":
            k = match(tokens, j, POST_ADVERBS)
            if k and not match(tokens, j, ("in front of", "behind the", "behind a", "behind it", "behind us")):
                j += k
                continue
        k = match(tokens, j, preps)
        prep = " ".join(tokens[j : j + k])
        if k and (prep not in exclude or prep in APPEARANCE_PREPOSITIONS and _appearance(tokens, j + k)) \
                and not is_quantity(tokens, j + k):
            end = chunk_np(tokens, j + k, "inner")
            if prep == "between" and end < n - 1 and tokens[end] == "and":
                end = max(end, chunk_np(tokens, end + 1, "inner"))
            while end < n - 1 and tokens[end] in ("and", ",") and _appearance(tokens, end + 1):
                end = chunk_np(tokens, end + 1, "inner")  # "in a red top *and black trousers*"
            if end > j + k and not (mode == "asset" and prep != "of" and _names_place(tokens[j + k : end])):
                j = end
                continue
        if mode != "target":
            break
        k = match(tokens, j, RELATIVES)
        if not k and tokens[j] == "not" and j + 1 < n and is_participle(tokens[j + 1]):
            k = 1  # "the person *not moving*": a description (a stationary person), not a negated edit
        if (k or is_participle(tokens[j])) and tokens[j] not in exclude:
            j = clause_tail(tokens, j + (k or 1), relative=bool(k))
            continue
        break
    return j


def _appearance(tokens: Sequence[str], i: int) -> bool:
    """Whether the noun phrase at ``i`` is a garment or a colour ("beige trousers", "a blue cap") -- part of
    the appearance before it, not a new object."""
    end = chunk_np(tokens, i, "inner")
    words = tokens[i:end]
    return bool(words) and (any(w in lex.GARMENTS for w in words)
                            or words[0] in COLOR_SYNONYMS and not any(w in NOUNS for w in words))


def _names_place(words: Sequence[str]) -> bool:
    """An appearance phrase that is a place ("in *the left lane*", "with *the bus*") and so not appearance."""
    return any(w in lex.PLACE_NOUNS or w in lex.NON_OBJECTS or w in NOUNS for w in words)


#: Words after which a verb form is a noun ("a *turn*", "its *speed*").
_NOUN_MARKERS = frozenset({"a", "an", "the", "its", "their", "his", "her"})
#: Adjectives after which some verb forms are nouns ("a right *turn*", "a full *stop*"); any other verb after
#: them starts the predicate ("the car taking a right *do* an emergency stop", "turning left *slow* down").
_ADJECTIVE_NOUNS: dict[str, frozenset[str]] = {
    **dict.fromkeys(("left", "right"), frozenset({"turn", "turns"})),
    **dict.fromkeys(("full", "complete", "dead", "sudden"), frozenset({"stop", "stops", "halt", "halts"})),
}
#: Words after which "turn" is the verb again ("the car on the right *turn* left").
_TURN_COMPLEMENTS = frozenset({"left", "right", "around", "back", "into", "onto"})
#: Words before "to" that keep "to <verb>" in a description ("the car waiting *to turn* left", "about to").
TO_KEEPERS = frozenset({"about", "ready", "able", "trying", "going", "waiting", "starting", "planning", "set"})
#: Words whose own complement is "to a stop / halt": "the truck *coming to a stop*", "the car *braking to a
#: halt*" still describe the object (unlike "bring the car turning *to a halt*").
COMING_TO_REST = frozenset({"coming", "braking", "slowing", "grinding", "rolling", "pulling", "drawing", "gliding",
                            "easing", "screeching"})


def _coming_to_rest(tokens: Sequence[str], j: int) -> bool:
    """Whether "to a stop / halt" at ``j`` completes a describing participle ("coming to a stop", "pulling *up* to
    a stop") rather than starting the verb's result."""
    before = [t for t in tokens[max(0, j - 2):j] if t not in ("up", "over", "in", "down")]
    return bool(before) and before[-1] in COMING_TO_REST


def _verb_as_noun(tokens: Sequence[str], j: int) -> bool:
    """Whether the verb form ``tokens[j]`` is a noun here ("making a right *turn*", "reducing its *speed*")."""
    before = tokens[j - 1]
    if before in _NOUN_MARKERS:
        return True
    after = tokens[j + 1] if j + 1 < len(tokens) else ""
    return tokens[j] in _ADJECTIVE_NOUNS.get(before, frozenset()) and after not in _TURN_COMPLEMENTS


def _to_verb(tokens: Sequence[str], j: int) -> bool:
    """Whether ``tokens[j]`` is the "to" of an infinitive predicate ("get the van at the junction *to* lower its
    speed"), not part of a description ("waiting to turn", "going to the junction")."""
    nxt = tokens[j + 1] if j + 1 < len(tokens) else ""
    return (tokens[j] == "to" and nxt in lex.PREDICATE_VERBS and not is_participle(nxt)
            and nxt not in ("be", "is", "are") and tokens[j - 1] not in TO_KEEPERS
            and not is_participle(tokens[j - 1]))


def clause_tail(tokens: Sequence[str], j: int, relative: bool) -> int:
    """End of a participle's or relative clause's complement: up to a modal, a base verb, a clause break."""
    n = len(tokens)
    first = j
    while j < n:
        t = tokens[j]
        if t == "and" and j + 1 < n and is_participle(tokens[j + 1]):  # "standing and waiting"
            j += 2
            continue
        if t == "to" and tokens[j - 1] in TO_KEEPERS:  # "waiting to turn left": still describing
            j += 2
            continue
        if (t in PUNCT or t in ("and", "but", "then") or match(tokens, j, lex.MODALS) and t != "to"
                or j > first and _to_verb(tokens, j) or match(tokens, j, lex.SCENE_PHRASES)
                or t in ("by", "for", "at", "to", "after", "within") and is_quantity(tokens, j + 1)  # "by 1 s"
                or _VERB_COMPLEMENT.match(" ".join(tokens[j:])) and not _coming_to_rest(tokens, j)):
            break
        if (t in lex.PREDICATE_VERBS and not (relative and j == first) and not is_participle(t)
                and not _verb_as_noun(tokens, j)):
            break
        j += 1
    return j


def words_from(text: str, start: int) -> list[re.Match[str]]:
    """The words of ``text[start:]`` up to any blanked word (one holding ``|``), as matches in ``text[start:]``."""
    words = []
    for m in re.finditer(r"\S+", text[start:]):
        if "|" in m.group(0):
            break
        words.append(m)
    return words


def np_after(text: str, start: int, exclude: Iterable[str] = (), mode: str = "target") -> tuple[str, int, int]:
    """The noun phrase (``mode`` as :func:`chunk_np`'s) that starts at the first word of ``text[start:]``, up to
    any blanked word (one holding ``|``): ``(phrase, its start, its end)`` as character offsets in ``text``;
    ``("", start, start)``: none."""
    words = words_from(text, start)
    tokens = [m.group(0) for m in words]
    stop = chunk_np(tokens, 0, mode, exclude=exclude) if tokens else 0
    if stop == 0:
        return "", start, start
    return " ".join(tokens[:stop]), start + words[0].start(), start + words[stop - 1].end()


def chunk_targets(tokens: Sequence[str], i: int, mode: str = "target",
                  exclude: Iterable[str] = ()) -> list[tuple[int, int]]:
    """Coordinated noun phrases from ``i`` ("the bus and the truck", "the bus, the van"): ``(start, end)`` each."""
    spans: list[tuple[int, int]] = []
    j = i
    while True:
        end = chunk_np(tokens, j, mode, exclude)
        if end == j:
            break
        spans.append((j, end))
        k = 2 if tuple(tokens[end : end + 2]) in ((",", "and"), ("and", "also")) else 1
        if end + k < len(tokens) and tokens[end] in (",", "and") and tokens[end + k - 1] in (",", "and") \
                and tokens[end + k] in COORDINATOR_STARTS:
            j = end + k
            continue
        break
    return spans


def _opening(tokens: Sequence[str], i: int) -> int:
    """``i`` past polite and connective openings ("then", "could you", "and also")."""
    while i < len(tokens):
        k = match(tokens, i, lex.OPENINGS)
        if not k or (tokens[i] in ("next", "first", "second") and i + 1 < len(tokens) and tokens[i + 1] in ("to",)):
            break
        i += k
    return i


#: Words that start a clause (op verbs, causatives, verbs taking their object first, predicate verbs).
_CLAUSE_VERBS = frozenset({p.split()[0] for p in (*lex.REMOVE_VERBS, *lex.INSERT_VERBS, *lex.REPLACE_VERBS,
                                                  *lex.CAUSATIVES, *lex.TARGET_FIRST_VERBS)}
                          | {v for v in lex.PREDICATE_VERBS if not v.endswith("s") or v in ("cross", "pass")}
                          | {"instead", "there", "i", "we", "let"}) - {"is", "are", "not", "no", "set"}
_KNOWN = frozenset(COLOR_SYNONYMS) | lex.HEAD_NOUNS | frozenset(p.split()[0] for p in NP_PREPOSITIONS)


def starts_clause(tokens: Sequence[str], i: int) -> bool:
    """Whether a new clause starts at ``tokens[i]`` (after a soft break)."""
    i = _opening(tokens, i)
    n = len(tokens)
    if i >= n:
        return False
    t = tokens[i]
    if t in _CLAUSE_VERBS:
        return not (t == "stop" and i + 1 < n and tokens[i + 1] in ("sign", "signs", "line"))
    if t in ("it", "they", "he", "she") and _predicate_start(tokens, i + 1):
        return True
    end = chunk_np(tokens, i, "target") if match(tokens, i, lex.DETERMINERS) or t in ("node", "object") else i
    if end > i and _predicate_start(tokens, end) and not (
            tokens[end] == "to" and not _predicate_start(tokens, end + 1)):
        return True
    return (t not in _KNOWN and not is_number(t) and i + 1 < n
            and tokens[i + 1] in ("the", "a", "an", "all", "every", "node", "object", "it", "them", "this"))


def _needs_predicate(current: Sequence[str], tokens: Sequence[str], i: int) -> bool:
    """Whether ``current`` is only a subject waiting for a predicate ("make the car", "the car") and the words
    at ``i`` are another subject sharing it ("... and the bus stop"), not a clause of their own."""
    i = _opening(tokens, i)
    if i >= len(tokens) or tokens[i] in _CLAUSE_VERBS:
        return False
    start = _opening(current, 0)
    start += match(current, start, lex.CAUSATIVES)
    return start < len(current) and chunk_np(current, start, "target") == len(current)


def split_clauses(tokens: Sequence[str]) -> list[list[str]]:
    """The clauses of a canonical prompt (module docstring), each with its openings dropped."""
    clauses: list[list[str]] = []
    current: list[str] = []

    def flush() -> None:
        if current:
            start = _opening(current, 0)
            if start < len(current):
                clauses.append(list(current[start:]))
            current.clear()

    i = 0
    while i < len(tokens):
        k = match(tokens, i, lex.HARD_BREAKS)
        if k and not (tokens[i] == "then" and not current):
            flush()
            i += k
            continue
        k = match(tokens, i, lex.SOFT_BREAKS)
        if k and current and starts_clause(tokens, i + k) and not _needs_predicate(current, tokens, i + k):
            flush()
            i += k
            continue
        current.append(tokens[i])
        i += 1
    flush()
    return clauses
