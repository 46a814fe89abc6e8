"""Graph algorithms over the explored structure (or a product with an automaton): strongly
connected components, fair cycles, shortest paths inside a set.  Iterative throughout: a
structure of a million configurations must not meet Python's recursion limit."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable, Sequence


def sccs(nodes: Iterable[int], succ: Callable[[int], Iterable[int]], keep: Callable[[int], bool]) -> list[list[int]]:
    """Tarjan's strongly connected components of the subgraph of nodes where `keep` holds,
    reachable from `nodes`; each component is a list of its nodes."""
    index: dict[int, int] = {}
    low: dict[int, int] = {}
    on_stack: set[int] = set()
    stack: list[int] = []
    out: list[list[int]] = []
    counter = 0
    for root in nodes:
        if root in index or not keep(root):
            continue
        work: list[tuple[int, Iterable[int]]] = [(root, iter(succ(root)))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            v, it = work[-1]
            advanced = False
            for w in it:
                if not keep(w):
                    continue
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(succ(w))))
                    advanced = True
                    break
                if w in on_stack and index[w] < low[v]:
                    low[v] = index[w]
            if advanced:
                continue
            work.pop()
            if work:
                u = work[-1][0]
                if low[v] < low[u]:
                    low[u] = low[v]
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                out.append(comp)
    return out


def nontrivial(comp: Sequence[int], succ: Callable[[int], Iterable[int]]) -> bool:
    """A component with a cycle: more than one node, or a node stepping to itself."""
    return len(comp) > 1 or comp[0] in succ(comp[0])


def path_within(
    start: int, goal: Callable[[int], bool], succ: Callable[[int], Iterable[int]], inside: Callable[[int], bool]
) -> list[int] | None:
    """A shortest path (start first, goal last; at least one step when `start` is a goal only
    through a cycle is not asked for) inside the nodes where `inside` holds."""
    if goal(start):
        return [start]
    parent: dict[int, int] = {start: -1}
    queue = deque([start])
    while queue:
        v = queue.popleft()
        for w in succ(v):
            if w in parent or not inside(w):
                continue
            parent[w] = v
            if goal(w):
                path = [w]
                while parent[path[-1]] != -1:
                    path.append(parent[path[-1]])
                return path[::-1]
            queue.append(w)
    return None


def cycle_through(
    start: int,
    sets: Sequence[Callable[[int], bool]],
    succ: Callable[[int], Iterable[int]],
    inside: Callable[[int], bool],
) -> list[int]:
    """A cycle from `start` back to it, inside one strongly connected component, visiting a node
    of each of `sets` on the way (start first, start again last)."""
    path = [start]
    for want in sets:
        if want(path[-1]) and len(path) > 1:
            continue
        leg = path_within(path[-1], want, succ, inside)
        assert leg is not None, "the component holds a node of every set"
        path += leg[1:]
    # back to the start, by at least one step
    back = _step_path(path[-1], start, succ, inside)
    return path + back[1:]


def _step_path(a: int, b: int, succ: Callable[[int], Iterable[int]], inside: Callable[[int], bool]) -> list[int]:
    """A shortest path of at least one step from a to b inside the component."""
    parent: dict[int, int] = {}
    queue: deque[int] = deque()
    for w in succ(a):
        if inside(w) and w not in parent:
            parent[w] = a
            queue.append(w)
    while queue:
        v = queue.popleft()
        if v == b:
            path = [v]
            while path[-1] != a or len(path) == 1:
                path.append(parent[path[-1]])
            return path[::-1]
        for w in succ(v):
            if inside(w) and w not in parent:
                parent[w] = v
                queue.append(w)
    raise AssertionError("a strongly connected component has a path between any two nodes")


def reachable_accepting_cycle(
    start: int, succ: Callable[[int], Sequence[int]], bits: Callable[[int], int], full: int
) -> bool:
    """Whether a cycle reachable from `start` meets every set: some strongly connected component
    with a cycle whose nodes' `bits`, together, make `full`."""
    for comp in sccs([start], succ, lambda _n: True):
        if not nontrivial(comp, succ):
            continue
        got = 0
        for n in comp:
            got |= bits(n)
        if got & full == full:
            return True
    return False
