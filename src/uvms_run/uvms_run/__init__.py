"""``uvms run``: the whole node graph in one process, in lockstep or real time, with its bars."""
