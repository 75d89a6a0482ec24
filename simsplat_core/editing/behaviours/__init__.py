"""The behaviours of the edit language, one module each: its declaration (``declaration.BehaviourDecl``), its
parser rule and, for a manoeuvre, its label check; and their registry (``registry``): the tables the parser, the
motion requests, the checks, the benchmark's prompts and the mining rule client read."""
