"""Ringer & Lasenby (2002), Sec. 3, Figs 3-5, rebuilt: a toe comes back in one camera, then two.

The scene. Two calibrated cameras (OpenCV pinholes, 1920 x 1080) on either side watch a
dancer's feet: right ankle and toe in view, the right shank hiding the left ankle from
camera 2. At the template (frame k-1) the left ankle and toe are unseen and their predicted
positions are off: the toe's by 18 mm across both cameras' rays, the ankle's in depth
along camera 1's ray through the toe. At frame k the left toe is detected in camera 1
only, at an image point nearer the ankle's prediction than the toe's; at frame k+1 it is
detected in both cameras, and the ankle stays hidden.

The window. One object per marker; a node is a set of views, at most one detection per
camera, holding those detections (two markers cannot share one), located by triangulation
(two views) or on the camera's ray nearest the prediction (one view, Ringer & Lasenby
2004). An arc i -> j costs eq. 10 summed over the cameras (eq. 7, 9) with the state
predicted from i (constant position, the tail node's location):

    seen in c:      |pi_c(x) - z|^2 / 2 s^2 + log 2 pi s^2 - log P_D(c) + log(lambda_FA / A)
    missed in c:    -log(1 - P_D(c))

(a detection's cost against its being a false alarm; a detection nobody takes costs
nothing), plus one constant per frame so every arc is >= 0. P_D is the occlusion-aware one
(``formulations.cameras.visibility``) with the right shank as the body. The state
re-estimated per hypothesis (Sec. 2.2) is the node's own 3D location, and eq. 13 is the
sum of arc costs along a path, so the ``mht`` formulation searches exactly the paper's
trellis.

Paper's outcome, checked here: at k the best association gives the detection to the ankle
and the correct one is second (Fig. 3); at k+1 the path through the second wins (Figs 4,
5); the frame-by-frame tracker (I = J = 1) keeps the error, I = J = 2 or 3 does not.
"""

import itertools

import numpy as np
import pytest
import scipy.sparse as sp

from formulations.cameras.camera import Camera
from formulations.cameras.rig import Rig
from formulations.cameras.visibility import Body, blur, detection_probability
from formulations.methods.dp_extended import DpExtended
from formulations.methods.mht import Mht
from formulations.window.objective import path_cost
from formulations.window.problem import OBSERVATION, OCCLUSION, SINK, SOURCE, WindowProblem

NAMES = ["right ankle", "right toe", "left ankle", "left toe"]
RA, RT, LA, LT = range(4)
SIGMA_PX, LAMBDA_D, LAMBDA_FA, GATE_PX = 2.0, 0.95, 0.1, 60.0
AREA = 1920 * 1080
SHANK = Body(start=np.array([[88.0, 159, 450]]), end=np.array([[88.0, 159, 100]]), radius=np.array([50.0]))


def _camera(centre, target, name):
    forward = (target - centre) / np.linalg.norm(target - centre)
    right = np.cross(forward, [0.0, 0, 1])
    right /= np.linalg.norm(right)
    r = np.stack([right, np.cross(forward, right), forward])
    k = np.array([[1500.0, 0, 960], [0, 1500, 540], [0, 0, 1]])
    return Camera(K=k, distortion=np.zeros(5), R=r, t=-r @ centre, image_size=(1920, 1080), name=name)


RIG = Rig.of([
    _camera(np.array([3000.0, -1200, 900]), np.array([0.0, 0, 100]), "camera 1"),
    _camera(np.array([1700.0, 1000, 700]), np.array([0.0, 0, 100]), "camera 2"),
])


def _scene():
    """Template positions (the predicted state), true positions at k and k+1, detections."""
    toe_k = np.array([-60.0, -40, 40])
    ray, ray_2 = ((toe_k - centre) / np.linalg.norm(toe_k - centre) for centre in RIG.centres)
    across = np.cross(ray, ray_2)  # normal to the epipolar plane: seen by both cameras
    across /= np.linalg.norm(across)
    template = np.array([
        [145.0, 159, 90], [290, 159, 30],
        toe_k + 150 * ray + 3 * across,  # the ankle predicted behind the toe on camera 1's ray
        toe_k + 18 * across,  # the toe predicted 18 mm off, across both cameras' rays
    ])
    toe_next = toe_k + np.array([6.0, 0, 3])
    seen = {1: [(RA, 0), (RA, 1), (RT, 0), (RT, 1), (LT, 0)], 2: [(RA, 0), (RA, 1), (RT, 0), (RT, 1), (LT, 0), (LT, 1)]}
    true = {1: np.vstack([template[:2], [np.nan] * 3, toe_k]), 2: np.vstack([template[:2], [np.nan] * 3, toe_next])}
    detections = {m: [[RIG.cameras[c].project(true[m][n][None])[0] for n, cc in seen[m] if cc == c] for c in range(2)]
                  for m in (1, 2)}
    return template, detections


def _window(template, detections):
    """The window of the module doc, and for each observation node its (camera, detection) views."""
    kind, obj, frame, location, views = [], [], [], [], []
    for n in range(len(NAMES)):
        kind.append(SOURCE), obj.append(n), frame.append(0), location.append(template[n]), views.append({})
        for m in (1, 2):
            near = [[-1] + [d for d, z in enumerate(detections[m][c])
                            if np.linalg.norm(RIG.cameras[c].project(template[n][None])[0] - z) < GATE_PX] for c in range(2)]
            for choice in itertools.product(*near):
                if max(choice) < 0:
                    continue
                seen = {c: d for c, d in enumerate(choice) if d >= 0}
                kind.append(OBSERVATION), obj.append(n), frame.append(m), views.append(seen)
                location.append(_locate(seen, detections[m], template[n]))
            kind.append(OCCLUSION), obj.append(n), frame.append(m), location.append(template[n]), views.append({})
        kind.append(SINK), obj.append(n), frame.append(3), location.append(template[n]), views.append({})
    kind, obj, frame, location = np.array(kind), np.array(obj), np.array(frame), np.array(location)
    tail, head = zip(*[(i, j) for i in range(len(kind)) for j in range(len(kind))
                       if obj[i] == obj[j] and frame[j] == frame[i] + 1])
    tail, head = np.array(tail), np.array(head)
    cost = np.array([_step_cost(location[i], obj[i], kind[j], views[j], detections.get(frame[j])) for i, j in zip(tail, head)])
    into_frames = frame[head] <= 2
    cost[into_frames] -= cost[into_frames].min()  # one constant per frame: every path pays it once per object
    resource = {(m, c, d): r for r, (m, c, d) in enumerate(
        (m, c, d) for m in (1, 2) for c in range(2) for d in range(len(detections[m][c])))}
    rows, cols = zip(*[(v, resource[frame[v], c, d]) for v in range(len(kind)) for c, d in views[v].items()])
    problem = WindowProblem(
        n_objects=len(NAMES), n_frames=2, node_kind=kind, node_object=obj, node_frame=frame, node_location=location,
        resources=sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(len(kind), len(resource))),
        arc_tail=tail, arc_head=head, arc_cost=cost, layout_pairs=np.zeros((0, 2), dtype=int), layout_weight=np.zeros(0),
    )
    return problem, views


def _locate(seen, found, prediction):
    if len(seen) == 2:
        normalised = np.stack([RIG.cameras[c].undistort(found[c][d][None])[0] for c, d in seen.items()])[None]
        return RIG.triangulate(normalised)[0]
    (c, d), = seen.items()
    return RIG.on_ray(c, RIG.cameras[c].undistort(found[c][d][None]), prediction[None])[0]


def _step_cost(state, n, head_kind, seen, found):
    """Eq. 10 over both cameras for marker n's next node, from the state ``state`` (module doc)."""
    if head_kind == SINK:
        return 0.0
    p_d = np.clip(detection_probability(SHANK, state[None], RIG.centres, LAMBDA_D, blur(7.0, 5.0))[0], 1e-3, LAMBDA_D)
    cost = 0.0
    for c in range(2):
        if c in seen:
            residual = RIG.cameras[c].project(state[None])[0] - found[c][seen[c]]
            cost += residual @ residual / (2 * SIGMA_PX**2) + np.log(2 * np.pi * SIGMA_PX**2) - np.log(p_d[c])
            cost += np.log(LAMBDA_FA / AREA)
        else:
            cost -= np.log1p(-p_d[c])
    return cost


def _who_took(problem, views, path, m, camera, detection):
    for n in range(problem.n_objects):
        if views[path[n, m - 1]].get(camera) == detection:
            return n
    return None


def test_the_toe_is_named_only_by_keeping_the_second_best_association():
    template, detections = _scene()
    problem, views = _window(template, detections)
    new = len(detections[1][0]) - 1  # camera 1's new detection at k (the toe's: listed last)

    # Fig. 3: at k alone, the best association gives the detection to the ankle, the second to the toe.
    ranked = _ranked_at_k(problem)
    assert [_who_took(views, path, 1, 0, new) for path in ranked[:2]] == [LA, LT]

    greedy = Mht(hypotheses=1, associations=1).solve(problem)
    assert _who_took(views, greedy.path, 1, 0, new) == LA  # the frame-by-frame tracker keeps the error
    exhaustive = DpExtended().solve(problem)  # the exact optimum of the same costs
    for i_j in (2, 3):
        solution = Mht(hypotheses=i_j, associations=i_j).solve(problem)
        assert _who_took(views, solution.path, 1, 0, new) == LT  # Fig. 5: the best path runs through the second
        assert _who_took(views, solution.path, 2, 0, new) == LT and _who_took(views, solution.path, 2, 1, 2) == LT
        assert _who_took(views, solution.path, 1, 0, new) != _who_took(views, greedy.path, 1, 0, new)
        assert solution.cost == pytest.approx(exhaustive.cost) and exhaustive.cost < greedy.cost - 1.0
        assert greedy.cost == pytest.approx(path_cost(problem, greedy.path))


def _who_took(views, path, m, camera, detection):
    """The marker whose node in frame m holds ``detection`` of ``camera``, or None."""
    takers = [n for n in range(len(path)) if views[path[n, m - 1]].get(camera) == detection]
    return takers[0] if takers else None


def _ranked_at_k(problem):
    """Every feasible choice of frame-k nodes, as paths (occluded at k+1), cheapest first by
    the frame-k arcs alone: eq. 3 at k by brute force."""
    first = [np.flatnonzero((problem.node_object == n) & (problem.node_frame == 1)) for n in range(problem.n_objects)]
    occluded = [np.flatnonzero((problem.node_object == n) & (problem.node_frame == 2) & (problem.node_kind == OCCLUSION))[0]
                for n in range(problem.n_objects)]
    into = {int(h): c for h, c, t in zip(problem.arc_head, problem.arc_cost, problem.node_kind[problem.arc_tail]) if t == SOURCE}
    paths = []
    for choice in itertools.product(*first):
        held = problem.resources[list(choice)].toarray().sum(axis=0)
        if (held <= 1).all():
            paths.append((sum(into[int(v)] for v in choice), np.column_stack([choice, occluded])))
    return [path for _, path in sorted(paths, key=lambda cost_path: cost_path[0])]
