import numpy as np, warnings
from qsa import Curve, Fourier, FiniteDifference
from qsa.energies import CanhamHelfrich, Pressure, Perimeter
from qsa.constraints import FixedLength
from qsa.spectra import spectrum
eps, R = 0.7, 1.3
p = 0.4
ks = np.arange(2, 8)
lam = np.repeat(-(ks**2-1)*(eps*(ks**2-1)/R**4 + p/R),2)
for N in [64,128,256]:
    c = Curve.circle(R, FiniteDifference(N))
    s = spectrum(CanhamHelfrich(eps) + Pressure(p), c, constraints=[FixedLength()])
    ev = np.sort(s.eigenvalues[~s.is_kernel])[::-1][:6]
    s0 = spectrum(CanhamHelfrich(eps) + Perimeter(1.0, 2*np.pi*R - eps/(2*R**2)), c)
    print(N, s.kernel_tol, s0.kernel_tol, np.abs(ev/lam[:6]-1).max(), s.eigenvalues[s.is_kernel])
