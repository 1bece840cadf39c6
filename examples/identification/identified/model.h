/* Identified by `bushing-sim identify` from the campaign "Identification truth: spline + 3 Maxwell + 4 Jenkins":
 * the parameters of model.toml as C constants. Units: mm, N, s;
 * corners in Hz (omega = 2 pi f). */
#ifndef BUSHING_MODEL_H
#define BUSHING_MODEL_H

#define BUSHING_MODEL_BACKBONE_POINTS 9
static const double bushing_model_backbone_x_mm[9] = {-4.5000000000000000e0, -3.3125000000000000e0, -2.1250000000000000e0, -9.3750000000000000e-1, 2.5000000000000000e-1, 1.4375000000000000e0, 2.6250000000000000e0, 3.8125000000000000e0, 5.0000000000000000e0};
static const double bushing_model_backbone_f_n[9] = {-1.0067736551769110e3, -7.0179112139101426e2, -4.0476555426982912e2, -1.7758338274375629e2, 4.7493873673443119e1, 2.7478319429248506e2, 5.3003560979048461e2, 8.2883106346087720e2, 1.1794569027788057e3};
#define BUSHING_MODEL_MAXWELL_CELLS 3
/* {corner Hz, fraction g} */
static const double bushing_model_maxwell_hz_g[3][2] = {{4.8825607049962327e-1, 9.6448691258933655e-2}, {4.7838582926697759e0, 1.2004384348298437e-1}, {4.7301478296133219e1, 8.2532312984304926e-2}};
#define BUSHING_MODEL_IWAN_CELLS 4
/* {fraction g, slip force N} */
static const double bushing_model_iwan_g_slip_n[4][2] = {{5.0574049440234539e-2, 6.6965407624889872e-1}, {5.0438520787280547e-2, 2.8229154707557438e0}, {6.1965014877593073e-2, 9.3064943865228429e0}, {5.9125240984828450e-2, 2.3068790657992075e1}};

#endif /* BUSHING_MODEL_H */
