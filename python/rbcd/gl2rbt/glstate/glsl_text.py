"""GLSL source as the converter's scans read it: what the compiler's
preprocessor leaves of the text, so that a word the scans look for
(`discard`, `gl_FragDepth`, `gl_ClipDistance`, `buffer`, `readonly`,
`atomic_uint`) is found however the source spells it: every line end Mesa's
preprocessor takes (LF, CR, CR LF, LF CR) a new line, lines joined where a
backslash ends them, comments gone, macros expanded (object-like and
function-like, `##` pasting, arguments over several lines), directives
dropped.

Conditionals are not evaluated: every branch is kept, and so is every
definition a macro has in any of them (an #undef removes none): the text
is read once for each choice, the first definition of every macro, the
second of every macro that has one, and so on (a branch's definitions
together), the readings one after another. The scans only ever widen (a
fragment shader that may discard, a stage that may store, a vertex shader
that may write clip distances), which is what the converter needs of
them: a word in a branch or definition the compiler drops costs a draw
counted as an upper bound or a refusal, never a silent wrong answer.

Bounded: macro expansion stops past MAX_TOKENS tokens more than the
source's or MAX_DEPTH macros inside one another (a macro that doubles
itself twenty times over); expanded() then raises ExpansionTooLarge."""
import re
from collections import Counter

MAX_TOKENS = 1 << 18    # tokens the expansion may add to the source's (game shaders' add hundreds)
MAX_DEPTH = 64          # macros expanded inside one another
MAX_PASSES = 8          # a text expanded again, until nothing changes
MAX_CHOICES = 64        # definitions of one macro (each a reading of the source)

COMMENTS = re.compile(r"//[^\n]*|/\*.*?\*/", re.S)
CONTINUATION = re.compile(r"\\\n")
LINE_ENDS = re.compile(r"\r\n|\n\r|\r")   # each a new line, as Mesa's preprocessor takes them
TOKEN = re.compile(r"[A-Za-z_]\w*|\d[\w.]*|##|\S")
DEFINE = re.compile(r"#\s*define\s+([A-Za-z_]\w*)(\(([^)]*)\))?(.*)", re.S)


class ExpansionTooLarge(Exception):
    pass


def expanded(source):
    """The source's text as the scans read it (tokens apart by spaces): one
    reading for each choice of definition, apart by `;`."""
    source = LINE_ENDS.sub("\n", source)
    if "define" not in source and "\\" not in source:
        return COMMENTS.sub(" ", source)   # nothing to join or expand
    text = COMMENTS.sub(" ", CONTINUATION.sub("", source))
    lines = text.split("\n")
    definitions = Counter(m.group(1) for m in (DEFINE.match(line.strip()) for line in lines) if m)
    choices = max(definitions.values(), default=1)
    budget = [MAX_TOKENS + len(TOKEN.findall(text))]
    if choices > MAX_CHOICES:
        raise ExpansionTooLarge()
    return "\n;\n".join(reading(lines, choice, budget) for choice in range(choices))


def reading(lines, choice, budget):
    """The lines with each macro's definition number `choice` (its last if
    it has fewer) wherever it is defined."""
    macros, out, segment = {}, [], []

    def flush():
        # The lines between two directives expanded as one text (a macro's
        # arguments may run over lines), again until nothing changes (an
        # expansion naming a function-like macro whose arguments follow).
        tokens = TOKEN.findall("\n".join(segment))
        for _ in range(MAX_PASSES):
            again = expand(tokens, macros, frozenset(), 0, budget)
            if again == tokens:
                break
            tokens = again
        budget[0] -= len(tokens)
        if budget[0] < 0:
            raise ExpansionTooLarge()
        out.append(" ".join(tokens))
        segment.clear()

    seen = {}
    for line in lines:
        stripped = line.strip()
        if not stripped.startswith("#"):
            segment.append(line)
            continue
        flush()
        m = DEFINE.match(stripped)
        if m:
            # (#undef and conditionals change nothing: every definition is
            # some reading's)
            name = m.group(1)
            seen[name] = seen.get(name, -1) + 1
            if seen[name] <= choice or name not in macros:
                params = None if m.group(2) is None else [p.strip() for p in m.group(3).split(",") if p.strip()]
                macros[name] = (params, TOKEN.findall(m.group(4)))
    flush()
    return "\n".join(out)


def expand(tokens, macros, hidden, depth, budget):
    """`tokens` with every macro not in `hidden` expanded, rescanned."""
    if depth > MAX_DEPTH:
        raise ExpansionTooLarge()
    out, i = [], 0
    while i < len(tokens):
        tok = tokens[i]
        i += 1
        macro = macros.get(tok) if tok not in hidden else None
        if macro is None:
            out.append(tok)
        else:
            params, body = macro
            if params is None:
                out += expand(paste(body), macros, hidden | {tok}, depth + 1, budget)
            elif i < len(tokens) and tokens[i] == "(":
                args, i = arguments(tokens, i + 1)
                out += expand(substitute(body, params, args, macros, hidden, depth, budget), macros,
                              hidden | {tok}, depth + 1, budget)
            else:
                out.append(tok)   # a function-like macro's name without arguments: itself
        if len(out) > budget[0]:
            raise ExpansionTooLarge()
    return out


def arguments(tokens, i):
    """The comma-separated arguments from tokens[i] (just past "(") to the
    matching ")", and the index past it (the line's end if it has none)."""
    args, current, level = [], [], 0
    while i < len(tokens):
        tok = tokens[i]
        i += 1
        if tok == ")" and level == 0:
            args.append(current)
            return args, i
        if tok == "," and level == 0:
            args.append(current)
            current = []
            continue
        level += tok == "("
        level -= tok == ")"
        current.append(tok)
    args.append(current)
    return args, i


def substitute(body, params, args, macros, hidden, depth, budget):
    """A function-like macro's body with its parameters replaced: an
    argument beside `##` as written, any other expanded first; then pasted."""
    out = []
    for k, tok in enumerate(body):
        if tok in params:
            arg = args[params.index(tok)] if params.index(tok) < len(args) else []
            beside = k > 0 and body[k - 1] == "##" or k + 1 < len(body) and body[k + 1] == "##"
            out += arg if beside else expand(arg, macros, hidden, depth + 1, budget)
        else:
            out.append(tok)
    return paste(out)


def paste(tokens):
    """`a ## b` made one token `ab`."""
    out = []
    k = 0
    while k < len(tokens):
        if tokens[k] == "##" and out and k + 1 < len(tokens):
            out[-1] += tokens[k + 1]
            k += 2
        elif tokens[k] == "##":
            k += 1
        else:
            out.append(tokens[k])
            k += 1
    return out


def conditional_on(sources, word):
    """Whether `word` may be in a stage's compiled text or not depending on
    the preprocessor's conditionals, which the scans do not evaluate: one
    of its shader objects' sources has a conditional, and the word is in
    one's condition or under one, in a macro's definition (which a
    conditional may use or not), or nowhere literally (made by ##
    pasting). False for sources without conditionals, or whose word
    stands outside them all."""
    texts = [COMMENTS.sub(" ", CONTINUATION.sub("", LINE_ENDS.sub("\n", s))) for s in sources]
    if not any(CONDITIONAL.search(text) for text in texts):
        return False
    found = False
    for text in texts:
        depth = 0
        for line in text.split("\n"):
            line = line.strip()
            if word in line and (depth or OPENS.match(line) or DEFINE.match(line)):
                return True
            if OPENS.match(line):
                depth += 1
            elif ENDS.match(line):
                depth = max(0, depth - 1)
            elif word in line:
                found = True
    return not found


CONDITIONAL = re.compile(r"^[ \t]*#[ \t]*(if|ifdef|ifndef)\b", re.M)
OPENS = re.compile(r"#\s*(if|ifdef|ifndef)\b")
ENDS = re.compile(r"#\s*endif\b")
