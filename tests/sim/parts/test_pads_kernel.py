"""The compiled walks of sim.parts.pads_kernel give what the (frames x samples) numpy arrays they replace gave,
to the bit: the same float32 coordinates, bars and sums in the same order."""

import numpy as np
import pytest
import trimesh

from sim.parts.grasp_synthesis import GraspSynthesisParams
from sim.parts.gripper_fit import Frames, Surface, ahead, box_limits, measure

PARAMS = GraspSynthesisParams()


def _coordinate(surface, frames, direction):
    offset = (frames.origins[:, 0] * direction[:, 0] + frames.origins[:, 1] * direction[:, 1]).astype(np.float32)
    direction = direction.astype(np.float32)
    return np.outer(direction[:, 0], surface.points[:, 0]) + np.outer(direction[:, 1], surface.points[:, 1]) \
        - offset[:, None]


def _pads_meet(surface, frames, p):
    count, c = len(frames.origins), frames.closing
    u, v = _coordinate(surface, frames, c), _coordinate(surface, frames, frames.across)
    w = surface.points[None, :, 2] - frames.origins[:, 2, None].astype(np.float32)
    band = (np.abs(v) <= p.pad_half_size[1]) & (np.abs(w) <= p.pad_half_size[2]) & (np.abs(u) < p.max_opening / 2)
    (f, s), u, v, w = np.nonzero(band), u[band], v[band], w[band]
    lo, hi = np.full(count, np.inf, u.dtype), np.full(count, -np.inf, u.dtype)
    np.minimum.at(lo, f, u)
    np.maximum.at(hi, f, u)
    facing = c[f, 0] * surface.normals[s, 0] + c[f, 1] * surface.normals[s, 1]
    at_lo = (u <= lo[f] + p.contact_tolerance) & (facing <= -p.cos_cone)
    at_hi = (u >= hi[f] - p.contact_tolerance) & (facing >= p.cos_cone)
    areas = np.column_stack([np.bincount(f[at_lo], minlength=count), np.bincount(f[at_hi], minlength=count)])
    touch = at_lo | at_hi
    touching = np.maximum(np.bincount(f[touch], minlength=count), 1)
    contact = np.column_stack([np.bincount(f[touch], v[touch], count), np.bincount(f[touch], w[touch], count)])
    return lo, hi, areas * surface.area_each, contact / touching[:, None]


def _collides(surface, frames, lo, hi, middle, p):
    (strip_v, strip_w, pad_v, pad_u_lo, pad_u_hi, pad_w_lo, fin_v, fin_u_lo, fin_u_hi, fin_w_lo, palm_v, palm_u,
     palm_w, fin_w_hi, finger_in) = box_limits(p)
    v = _coordinate(surface, frames, frames.across)
    w = surface.points[None, :, 2] - frames.origins[:, 2, None].astype(np.float32)
    strip = (np.abs(v) <= strip_v) & (w >= strip_w)
    f, av, w = np.nonzero(strip)[0], np.abs(v[strip]), w[strip]
    u = _coordinate(surface, frames, frames.closing)[strip] - middle[f]
    au = np.abs(u)
    hit = (av <= pad_v) & (au >= pad_u_lo) & (au <= pad_u_hi) & (w >= pad_w_lo)
    hit |= (av <= fin_v) & (au >= fin_u_lo) & (au <= fin_u_hi) & (w >= fin_w_lo)
    hit |= (av <= palm_v) & (au <= palm_u) & (w >= palm_w)
    sweep = (av <= fin_v) & (w >= fin_w_lo) & (w <= fin_w_hi) & (au <= fin_u_hi)
    hit |= sweep & ((u >= hi[f] + finger_in) | (u <= lo[f] - finger_in))
    return np.bincount(f[hit], minlength=len(frames.origins)) > 0


def _ahead(surface, seeds, p):
    tube, tol = 1.5 * np.sqrt(surface.area_each), p.contact_tolerance
    reach = p.max_opening / 2 + p.finger_offset[0] + p.finger_half_size[0] + p.clearance
    lane, z = p.finger_half_size[1] + p.clearance, surface.points[:, 2]
    u, v = _coordinate(surface, seeds, seeds.closing), _coordinate(surface, seeds, seeds.across)
    f, s = np.nonzero((np.abs(v) <= tube) & (np.abs(z - seeds.origins[:, 2, None]) <= tube) & (u > tol))
    leaving = (seeds.closing[f] * surface.normals[s, :2]).sum(1) >= p.cos_cone
    span = np.full(len(seeds.origins), np.inf, np.float32)
    np.minimum.at(span, f[leaving], u[f[leaving], s[leaving]])
    d = span[:, None]
    beside = (np.abs(v) <= lane) & ((u < -tol) | (u > d + tol)) & (np.abs(u - d / 2) <= reach) \
        & (z < seeds.origins[:, 2, None])
    return span, np.where(beside, z, 0.0).max(1)


@pytest.fixture(scope="module")
def part():
    """A bracket-like part (a plate and an upright with a slot) sampled as the synthesis samples it, and
    frames at surface points facing every way."""
    plate = trimesh.creation.box((0.06, 0.04, 0.008))
    upright = trimesh.creation.box((0.01, 0.04, 0.05))
    upright.apply_translation((0.02, 0.0, 0.025))
    mesh = trimesh.util.concatenate([plate, upright])
    rng = np.random.default_rng(3)
    surface = Surface.sample(mesh, rng, PARAMS)
    origins = surface.points[rng.choice(len(surface.points), 300)].astype(np.float64)
    angle = rng.uniform(0, 2 * np.pi, len(origins))
    return surface, Frames(origins, np.column_stack([np.cos(angle), np.sin(angle)]))


def test_the_pads_stops_and_contacts_are_the_arrays_to_the_bit(part):
    surface, frames = part
    fit = measure(surface, frames, PARAMS)
    lo, hi, areas, contact = _pads_meet(surface, frames, PARAMS)
    for got, want in ((fit.lo, lo), (fit.hi, hi), (fit.areas, areas), (fit.contact, contact)):
        assert got.dtype == want.dtype and np.array_equal(got, want)
    assert np.isfinite(lo).sum() > 100 and (areas > 0).any()  # the frames meet the part


@pytest.mark.parametrize("centred", [True, False])
def test_the_gripper_hits_the_part_where_the_arrays_said(part, centred):
    surface, frames = part
    fit = measure(surface, frames, PARAMS, min_area=surface.area_each, centred=centred)
    lo, hi, areas, _ = _pads_meet(surface, frames, PARAMS)
    test = np.isfinite(lo) & (hi - lo <= PARAMS.widest) & (areas.min(1) >= surface.area_each)
    middle = (lo[test] + hi[test]) / 2 if centred else np.zeros(int(test.sum()), lo.dtype)
    want = np.zeros(len(lo), bool)
    want[test] = _collides(surface, frames.take(test), lo[test] - middle, hi[test] - middle, middle, PARAMS)
    assert np.array_equal(fit.collides, want)
    assert 0 < want.sum() < test.sum()  # some placements hit the upright, some do not


def test_what_lies_ahead_of_each_seed_is_the_arrays_to_the_bit(part):
    surface, frames = part
    span, floor = ahead(surface, frames, PARAMS)
    want_span, want_floor = _ahead(surface, frames, PARAMS)
    assert np.array_equal(span, want_span) and np.array_equal(floor, want_floor)
    assert np.isfinite(span).any() and (floor > 0).any()
