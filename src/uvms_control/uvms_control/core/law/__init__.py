"""The unified force controller: laws, fuzzy switch, references (imports no ``core.task``)."""
