"""Writes eidors_stim.mat and eidors_stim_v6.mat: EIDORS's stimulation struct arrays as
MATLAB keeps them, written by SciPy's savemat (an independent writer of the MATLAB format),
for et's tests: compressed (MATLAB's default, -v7) and not (-v6; the fuzz target's seed);
eidors_fmdl.mat, the forward model alone; and eidors_one.mat, a stimulation of one injection.

EIDORS's mk_stim_patterns(n_elec, 1, inj, meas, options, amplitude), ported from its
documented behaviour (its own unit tests: mk_stim_patterns(4,1,[0,1],[0,1],{},1) gives
stim(1).stim_pattern = [-1;1;0;0] and stim(1).meas_pattern = [0,0,1,-1]):
  stim(k).stimulation  = 'Amp'
  stim(k).stim_pattern = sparse L x 1: -amplitude at electrode k, +amplitude at k+1 (1-based,
                         adjacent drive)
  stim(k).meas_pattern = sparse M x L: a row per measurement, +1 at electrode j, -1 at j+1,
                         the rows on drive electrodes left out (no_meas_current, the default);
                         with rotate_meas, measurement j is taken from electrode k + j.

Variables:
  stim   adjacent drive and measurement, 16 electrodes, 10 mA (the default amplitude), as
         `stim = mk_stim_patterns(16,1,'{ad}','{ad}',{},0.010)`
  fmdl   a forward model's struct whose `stimulation` is
         `mk_stim_patterns(8,1,'{op}','{ad}',{'rotate_meas','meas_current'},0.001)`, beside
         other fields (`name`, `nodes`) as a fwd_model has
  vi     frames as a loop's `vi(k) = fwd_solve(img)` keeps them: a 1 x 3 struct array of
         EIDORS data structs (`name`, `meas` 208 x 1 V, `time`), meas(j) of frame k being
         1e-3 * (k + 1) + 1e-6 * j
Run: python make_eidors_stim.py (needs numpy and scipy); the files are committed (a run
writes its date into the files' headers, the rest byte for byte).
"""
import numpy as np
import scipy.io
import scipy.sparse as sp


def mk_stim_patterns(n, inj, meas, rotate, meas_current, amplitude):
    stim = []
    for elec in range(n):
        s = np.zeros((n, 1))
        s[(inj[0] + elec) % n, 0] = -amplitude
        s[(inj[1] + elec) % n, 0] = amplitude
        drive = {(inj[0] + elec) % n, (inj[1] + elec) % n}
        ofs = elec if rotate else 0
        rows = []
        for j in range(n):
            p, q = (meas[0] + j + ofs) % n, (meas[1] + j + ofs) % n
            if not meas_current and ({p, q} & drive):
                continue
            r = np.zeros(n)
            r[p], r[q] = 1.0, -1.0
            rows.append(r)
        stim.append(("Amp", sp.csc_matrix(s), sp.csc_matrix(np.array(rows))))
    dtype = [("stimulation", object), ("stim_pattern", object), ("meas_pattern", object)]
    out = np.empty((1, len(stim)), dtype=dtype)
    for k, fields in enumerate(stim):
        out[0, k] = fields
    return out


stim = mk_stim_patterns(16, (0, 1), (0, 1), False, False, 0.010)
fmdl = {
    "name": "an 8-electrode tank",
    "nodes": np.random.default_rng(1).random((20, 2)),
    "stimulation": mk_stim_patterns(8, (0, 4), (0, 1), True, True, 0.001),
}
vi = np.empty((1, 3), dtype=[("name", object), ("meas", object), ("time", object)])
for k in range(3):
    vi[0, k] = ("solved", (1e-3 * (k + 1) + 1e-6 * np.arange(208)).reshape(208, 1), float(k))
for name, compressed in [("eidors_stim.mat", True), ("eidors_stim_v6.mat", False)]:
    scipy.io.savemat(name, {"stim": stim, "fmdl": fmdl, "vi": vi}, do_compression=compressed,
                     oned_as="column")
# A forward model alone (its nodes and its stimulation, no frames), and a stimulation of one
# injection (a 1 x 1 struct): said as a protocol's file where frames are read.
scipy.io.savemat("eidors_fmdl.mat", {"fmdl": fmdl}, do_compression=True, oned_as="column")
one = mk_stim_patterns(4, (0, 1), (0, 1), False, False, 0.001)[:, :1]
scipy.io.savemat("eidors_one.mat", {"one": one}, do_compression=True, oned_as="column")
