/* Identified by `bushing-sim identify` from the campaign "Identification truth: spline + 3 Maxwell + 4 Jenkins":
 * the parameters of model.toml as C constants. Units: mm, N, s;
 * corners in Hz (omega = 2 pi f). */
#ifndef BUSHING_MODEL_H
#define BUSHING_MODEL_H

#define BUSHING_MODEL_BACKBONE_POINTS 9
static const double bushing_model_backbone_x_mm[9] = {-4.5000000000000000e0, -3.3125000000000000e0, -2.1250000000000000e0, -9.3750000000000000e-1, 2.5000000000000000e-1, 1.4375000000000000e0, 2.6250000000000000e0, 3.8125000000000000e0, 5.0000000000000000e0};
static const double bushing_model_backbone_f_n[9] = {-1.0128352780053801e3, -7.0059438694114976e2, -4.0494520349131136e2, -1.7759262078838378e2, 4.7506366667850727e1, 2.7479428530524638e2, 5.3005618877165966e2, 8.2885560075571755e2, 1.1794883552497799e3};
#define BUSHING_MODEL_MAXWELL_CELLS 3
/* {corner Hz, fraction g} */
static const double bushing_model_maxwell_hz_g[3][2] = {{4.8824973972737973e-1, 9.6448817365882067e-2}, {4.7837891483672070e0, 1.2004500443457215e-1}, {4.7301351242736722e1, 8.2533302288931812e-2}};
#define BUSHING_MODEL_IWAN_CELLS 4
/* {fraction g, slip force N} */
static const double bushing_model_iwan_g_slip_n[4][2] = {{5.0574737171742143e-2, 6.6964485451507105e-1}, {5.0418048751129430e-2, 2.8196107751159953e0}, {6.2014417976114421e-2, 9.3152807273346543e0}, {5.9105681919097076e-2, 2.3067571621931357e1}};

#endif /* BUSHING_MODEL_H */
