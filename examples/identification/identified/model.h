/* Identified by `bushing-sim identify` from the campaign "Identification truth: spline + 3 Maxwell + 4 Jenkins":
 * the parameters of model.toml as C constants. Units: mm, N, s;
 * corners in Hz (omega = 2 pi f). */
#ifndef BUSHING_MODEL_H
#define BUSHING_MODEL_H

#define BUSHING_MODEL_BACKBONE_POINTS 9
static const double bushing_model_backbone_x_mm[9] = {-4.5000000000000000e0, -3.3125000000000000e0, -2.1250000000000000e0, -9.3750000000000000e-1, 2.5000000000000000e-1, 1.4375000000000000e0, 2.6250000000000000e0, 3.8125000000000000e0, 5.0000000000000000e0};
static const double bushing_model_backbone_f_n[9] = {-1.0130318788722275e3, -7.0029031717335874e2, -4.0515271055332647e2, -1.7764154621396148e2, 4.7484253636055968e1, 2.7458187595689492e2, 5.2977353540111596e2, 8.2873418213510968e2, 1.1794088979474718e3};
#define BUSHING_MODEL_MAXWELL_CELLS 3
/* {corner Hz, fraction g} */
static const double bushing_model_maxwell_hz_g[3][2] = {{4.8827319833613614e-1, 9.6460256653982168e-2}, {4.7841774208376151e0, 1.2005029860139267e-1}, {4.7300902074317925e1, 8.2538540750283773e-2}};
#define BUSHING_MODEL_IWAN_CELLS 4
/* {fraction g, slip force N} */
static const double bushing_model_iwan_g_slip_n[4][2] = {{5.0581229249526030e-2, 6.6967788969806918e-1}, {5.0461587421160227e-2, 2.8255875046696799e0}, {6.2119616903167425e-2, 9.3372793061222232e0}, {5.9194736013548785e-2, 2.3370808297568743e1}};

#endif /* BUSHING_MODEL_H */
