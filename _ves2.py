import numpy as np, warnings
from qsa import Curve, Fourier, FiniteDifference
from qsa.energies import CanhamHelfrich
from qsa.constraints import FixedLength, FixedArea
from qsa.equilibria import polish
from qsa.spectra import spectrum, kernel_report
def ellipse(grid, a, b):
    return Curve.polar(lambda t: a*b/np.sqrt((b*np.cos(t))**2+(a*np.sin(t))**2), grid)
L = 2*np.pi; nu=0.9; A = nu*L**2/(4*np.pi)
cons=[FixedLength(L), FixedArea(A)]
for grid in [Fourier(65), Fourier(129), FiniteDifference(128), FiniteDifference(256)]:
    r = polish(CanhamHelfrich(1.0), ellipse(grid, 1.25, 0.8), constraints=cons)
    s = spectrum(r.energy, r.curve, constraints=cons)
    print(grid, r.success, r.multipliers, s.n_kernel, s.n_unstable, s.kernel_tol, s.status)
    print('  ', np.sort(s.eigenvalues)[::-1][:8])
    print('  ', s.kernel.reparameterization, s.kernel.rigid_normal, s.kernel.lagrange_kernel)
