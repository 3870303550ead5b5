import numpy as np, warnings
from qsa import Curve, Fourier, FiniteDifference
from qsa.energies import CanhamHelfrich, Pressure, Perimeter
from qsa.constraints import FixedLength
from qsa.spectra import spectrum, kernel_report
eps, R = 0.7, 1.3
p = 0.4
ks = np.arange(2, 8)
lam = np.repeat(-(ks**2-1)*(eps*(ks**2-1)/R**4 + p/R),2)
c = Curve.circle(R, Fourier(33))
E = CanhamHelfrich(eps) + Pressure(p)
for gauge in ["comoving", "scaled", "paper", "normal"]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = spectrum(E, c, gauge=gauge, constraints=[FixedLength()])
    ev = np.real(s.eigenvalues[~s.is_kernel])
    ev = np.sort(ev[np.abs(ev)>1e-6])[::-1][:6]
    print(gauge, s.n_kernel, s.status, ev, lam[:6])
    print("   ", s.message[:300])
kr = kernel_report(E, c, constraints=[FixedLength()])
print(kr)
for p in [-0.3]:
    s = spectrum(CanhamHelfrich(eps)+Pressure(p), c, k=6, constraints=[FixedLength()])
    print(s.eigenvalues, s.is_kernel, s.method, np.repeat(-(ks**2-1)*(eps*(ks**2-1)/R**4 + p/R),2)[:4])
