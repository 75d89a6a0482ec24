"""The behaviours of the edit language, one declaration each (``declaration.BehaviourDecl``), and their registry
(``registry``): the tables the parser, the motion requests, the benchmark's prompts and the mining rule client
read."""
