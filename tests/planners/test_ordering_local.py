"""The plain-tour local search of the visiting order (seed 002 §3.4): the savings start, reversals, chains undone,
moves that gain exactly what they claim and never lengthen the tour, kicks that are kept only when no worse,
determinism under a seed, and the optimum found beyond the exact solver's reach."""

import random

import numpy as np
import pytest

from planners.ordering import distance_matrix, held_karp, solve_tsp, tour_cost
from planners.ordering.construct import greedy_tour, savings_tour
from planners.ordering.costs import neighbour_lists
from planners.ordering.local import ClosedTour, iterated_local_search


def random_points(n, seed):
    return np.random.default_rng(seed).random((n, 2)) * 100.0


def closed_tour(n, seed, order=None, depth=6):
    cost = distance_matrix(random_points(n, seed))
    near = neighbour_lists(cost, 10)
    start = list(np.random.default_rng(seed + 1).permutation(n)) if order is None else order
    return ClosedTour(cost.tolist(), near, [int(v) for v in start], (6, 5), depth), cost


def edges(order):
    return {frozenset((order[i - 1], order[i])) for i in range(len(order))}


@pytest.mark.parametrize("n", [4, 5, 30, 120])
def test_savings_tour_visits_every_stop_once(n):
    cost = distance_matrix(random_points(n, n))
    order = savings_tour(cost, neighbour_lists(cost, min(10, n - 1)))
    assert sorted(order) == list(range(n))


def test_savings_start_is_shorter_than_greedy_edge_start_on_most_random_fields():
    wins = 0
    for seed in range(8):
        cost = distance_matrix(random_points(150, seed))
        near = neighbour_lists(cost, 10)
        wins += tour_cost(savings_tour(cost, near), cost, True) < tour_cost(greedy_tour(cost, near), cost, True)
    assert wins >= 6


def test_flips_exchange_two_edges_and_keep_positions_consistent_even_across_the_wrap():
    tour, _ = closed_tour(40, 3)
    rng = random.Random(0)
    wrapped = False
    for _ in range(60):
        pa = rng.randrange(tour.n)
        pc = (pa + rng.randrange(2, tour.n - 1)) % tour.n
        wrapped |= pc < pa
        t = tour.order
        a, b, c, d = t[pa], t[(pa + 1) % tour.n], t[pc], t[(pc + 1) % tour.n]
        old = edges(t)
        tour.flip(a, b, c, d)
        new = edges(tour.order)
        assert old - new == {frozenset((a, b)), frozenset((c, d))}
        assert new - old == {frozenset((a, c)), frozenset((b, d))}
        assert all(tour.order[tour.pos[v]] == v for v in range(tour.n))
    assert wrapped


def test_a_chain_that_ends_worse_leaves_the_tour_as_it_was():
    tour, _ = closed_tour(60, 4)
    while any(tour.improve(t1) is not None for t1 in range(tour.n)):   # down to a local optimum, where every
        pass                                                            # chain tried ends worse
    before, positions = tour.order[:], tour.pos[:]
    assert all(tour.improve(t1) is None for t1 in range(tour.n))
    assert tour.order == before and tour.pos == positions


@pytest.mark.parametrize("depth", [1, 6])
def test_each_move_gains_exactly_what_it_reports_and_never_lengthens_the_tour(depth):
    tour, cost = closed_tour(80, 5, depth=depth)
    length = tour.length()
    moves = 0
    for _ in range(20):
        for t1 in range(tour.n):
            found = tour.improve(t1)
            now = tour.length()
            if found is None:
                assert now == pytest.approx(length, abs=1e-9)
                continue
            moves += 1
            assert found[0] > 0.0 and now == pytest.approx(length - found[0], abs=1e-6)
            length = now
    assert moves > 0 and sorted(tour.order) == list(range(tour.n))
    assert all(tour.improve(t1) is None for t1 in range(tour.n))         # a local optimum


def test_double_bridge_reports_its_cost_change_and_reorders_three_segments():
    tour, _ = closed_tour(30, 7, order=list(range(30)))
    delta, touched = tour.double_bridge(2, 4, 5, 6)
    assert sorted(tour.order) == list(range(30)) and len(set(touched)) == 8
    assert tour.length() - tour_cost(list(range(30)), distance_matrix(random_points(30, 7)), True) == \
        pytest.approx(delta)
    assert {frozenset((2, 12)), frozenset((17, 7)), frozenset((11, 3)), frozenset((6, 18))} <= edges(tour.order)


def test_iterated_search_keeps_only_kicks_that_do_not_lengthen_the_tour():
    tour, _ = closed_tour(100, 9)
    assert tour.optimise(range(tour.n)) > 0.0
    local_optimum = tour.length()
    gain = iterated_local_search(tour, random.Random(1), 60, 30)
    assert tour.length() <= local_optimum + 1e-9
    assert gain == pytest.approx(local_optimum - tour.length(), abs=1e-6)
    assert sorted(tour.order) == list(range(tour.n)) and all(tour.order[tour.pos[v]] == v for v in range(tour.n))


def test_plain_tours_are_deterministic_under_a_seed():
    pts = random_points(120, 11)
    first = solve_tsp(pts, seed=4)
    assert solve_tsp(pts, seed=4) == first
    assert solve_tsp(pts, seed=4, closed=False, start=5) == solve_tsp(pts, seed=4, closed=False, start=5)


def test_heuristic_finds_the_optimum_just_beyond_the_exact_solvers_reach():
    hits = 0
    for seed in range(6):
        cost = distance_matrix(random_points(16, 300 + seed))                 # 15 stops besides the start
        exact = held_karp(cost, 0, closed=True).cost
        ours = solve_tsp(cost=cost, seed=seed)
        assert not ours.exact and ours.cost >= exact - 1e-9
        hits += ours.cost <= exact + 1e-9
    assert hits >= 5
