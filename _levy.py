import numpy as np, warnings
from qsa import Curve, Fourier, FiniteDifference
from qsa.energies import CanhamHelfrich, Pressure
from qsa.constraints import FixedLength
from qsa.spectra import spectrum, kernel_report, linearization
eps, R = 0.7, 1.3
for grid in [Fourier(65), FiniteDifference(128)]:
  for p in [-3*eps/R**3*0.5, 0.4]:
    c = Curve.circle(R, grid)
    E = CanhamHelfrich(eps) + Pressure(p)
    s = spectrum(E, c, constraints=[FixedLength()])
    ks = np.arange(2, 8)
    lam = -(ks**2-1)*(eps*(ks**2-1)/R**4 + p/R)
    print(grid, p, s.status, s.n_kernel, s.n_unstable, s.eigenvalues.size, s.message[:200])
    ev = s.eigenvalues[~s.is_kernel]
    ev = np.sort(ev)[::-1]
    print(' got ', ev[:8])
    print(' want', np.repeat(lam,2)[:8])
