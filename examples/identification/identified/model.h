/* Identified by `bushing-sim identify` from the campaign "Identification truth: spline + 3 Maxwell + 4 Jenkins":
 * the parameters of model.toml as C constants. Units: mm, N, s;
 * corners in Hz (omega = 2 pi f). */
#ifndef BUSHING_MODEL_H
#define BUSHING_MODEL_H

#define BUSHING_MODEL_BACKBONE_POINTS 9
static const double bushing_model_backbone_x_mm[9] = {-4.5000000000000000e0, -3.3125000000000000e0, -2.1250000000000000e0, -9.3750000000000000e-1, 2.5000000000000000e-1, 1.4375000000000000e0, 2.6250000000000000e0, 3.8125000000000000e0, 5.0000000000000000e0};
static const double bushing_model_backbone_f_n[9] = {-1.0292511086132772e3, -7.0023752121626978e2, -4.1557705272404922e2, -1.7891895366282279e2, 4.7627411525993850e1, 2.7613114948765696e2, 5.3226861970828259e2, 8.3238791741283080e2, 1.1843922553975981e3};
#define BUSHING_MODEL_MAXWELL_CELLS 3
/* {corner Hz, fraction g} */
static const double bushing_model_maxwell_hz_g[3][2] = {{4.7853756008567949e-1, 9.5775335355524766e-2}, {4.7618413421164050e0, 1.1951036819240136e-1}, {4.6450720740481863e1, 8.0999818328135326e-2}};
#define BUSHING_MODEL_IWAN_CELLS 4
/* {fraction g, slip force N} */
static const double bushing_model_iwan_g_slip_n[4][2] = {{4.3156931487892611e-2, 4.0460127583454525e-1}, {5.8245663588469956e-2, 2.5718913660869736e0}, {6.6183134735420729e-2, 9.7475479712888653e0}, {5.9197328418300423e-2, 2.3068846406179773e1}};

#endif /* BUSHING_MODEL_H */
