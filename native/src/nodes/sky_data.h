// Physical data of the Nishita sky model as Blender's sky library (intern/sky, used by Cycles 3.4's Sky Texture)
// samples it: 21 wavelengths from 380 to 780 nm in steps of 20 nm. These are measured or standard values, not
// code: the solar spectral irradiance at the top of the atmosphere (W m^-2 nm^-1), the Rayleigh scattering
// coefficient of air at sea level and the ozone absorption coefficient (m^-1) at each wavelength, the CIE 1931
// 2-degree colour matching functions x̄, ȳ, z̄ at each wavelength, and the 8-point Gauss–Laguerre rule (nodes
// x_i / 25 and weights w_i e^{x_i} / 25) with which the optical depth towards the sun is integrated. They must
// be the values Blender uses for the precomputed sky to agree with Cycles, hence repeated here. Internal to
// nodes/sky_texture.cpp.
#pragma once

namespace ps::sky_data {

constexpr int kWavelengths = 21;
constexpr float kFirstWavelength = 380.0f;  // nm
constexpr float kWavelengthStep = 20.0f;    // nm

// Solar irradiance above the atmosphere, W m^-2 nm^-1.
constexpr float kSunIrradiance[kWavelengths] = {
    1.45756829855592995315f, 1.56596305559738380175f, 1.65148449067670455293f, 1.71496242737209314555f,
    1.75797983805020541226f, 1.78256407885924539336f, 1.79095108475838560302f, 1.78541550133410664714f,
    1.76815554864306845317f, 1.74122069647250410362f, 1.70647127164943679389f, 1.66556087452739887134f,
    1.61993437242451854274f, 1.57083597368892080581f, 1.51932335059305478886f, 1.46628494965214395407f,
    1.41245852740172450623f, 1.35844961970384092709f, 1.30474913844739281998f, 1.25174963272610817455f,
    1.19975998755420620867f};

// Rayleigh scattering coefficient at sea level, m^-1.
constexpr float kRayleighScattering[kWavelengths] = {
    0.00005424820087636473f, 0.00004418549866505454f, 0.00003635151910165377f, 0.00003017929012024763f,
    0.00002526320226989157f, 0.00002130859310621843f, 0.00001809838025320633f, 0.00001547057129129042f,
    0.00001330284977336850f, 0.00001150184784075764f, 0.00000999557429990163f, 0.00000872799973630707f,
    0.00000765513700977967f, 0.00000674217203751443f, 0.00000596134125832052f, 0.00000529034598065810f,
    0.00000471115687557433f, 0.00000420910481110487f, 0.00000377218381260133f, 0.00000339051255477280f,
    0.00000305591531679811f};

// Ozone absorption coefficient at the peak of the ozone layer, m^-1.
constexpr float kOzoneAbsorption[kWavelengths] = {
    0.00000000325126849861f, 0.00000000585395365047f, 0.00000001977191155085f, 0.00000007309568762914f,
    0.00000020084561514287f, 0.00000040383958096161f, 0.00000063551335912363f, 0.00000096707041180970f,
    0.00000154797400424410f, 0.00000209038647223331f, 0.00000246128056164565f, 0.00000273551299461512f,
    0.00000215125863128643f, 0.00000159051840791988f, 0.00000112356197979857f, 0.00000073527551487574f,
    0.00000046450130357806f, 0.00000033096079921048f, 0.00000022512612292678f, 0.00000014879129266490f,
    0.00000016828623364192f};

// CIE 1931 colour matching functions x̄, ȳ, z̄ at 380, 400, ..., 780 nm.
constexpr float kCieXyz[kWavelengths][3] = {
    {0.00136800000f, 0.00003900000f, 0.00645000100f}, {0.01431000000f, 0.00039600000f, 0.06785001000f},
    {0.13438000000f, 0.00400000000f, 0.64560000000f}, {0.34828000000f, 0.02300000000f, 1.74706000000f},
    {0.29080000000f, 0.06000000000f, 1.66920000000f}, {0.09564000000f, 0.13902000000f, 0.81295010000f},
    {0.00490000000f, 0.32300000000f, 0.27200000000f}, {0.06327000000f, 0.71000000000f, 0.07824999000f},
    {0.29040000000f, 0.95400000000f, 0.02030000000f}, {0.59450000000f, 0.99500000000f, 0.00390000000f},
    {0.91630000000f, 0.87000000000f, 0.00165000100f}, {1.06220000000f, 0.63100000000f, 0.00080000000f},
    {0.85444990000f, 0.38100000000f, 0.00019000000f}, {0.44790000000f, 0.17500000000f, 0.00002000000f},
    {0.16490000000f, 0.06100000000f, 0.00000000000f}, {0.04677000000f, 0.01700000000f, 0.00000000000f},
    {0.01135916000f, 0.00410200000f, 0.00000000000f}, {0.00289932700f, 0.00104700000f, 0.00000000000f},
    {0.00069007860f, 0.00024920000f, 0.00000000000f}, {0.00016615050f, 0.00006000000f, 0.00000000000f},
    {0.00004150994f, 0.00001499000f, 0.00000000000f}};

// Gauss–Laguerre quadrature of order 8, its abscissae x_i scaled by 1/25 (so the last node lies inside the
// segment) and its weights w_i multiplied by e^{x_i} / 25.
constexpr int kQuadratureNodes = 8;
constexpr float kQuadratureAt[kQuadratureNodes] = {0.006811185292f, 0.03614807107f, 0.09004346519f,
                                                    0.1706680068f,  0.2818362161f,  0.4303406404f,
                                                    0.6296271457f,  0.9145252695f};
constexpr float kQuadratureWeight[kQuadratureNodes] = {0.01750893642f, 0.04135477391f, 0.06678839063f,
                                                        0.09507698807f, 0.1283416365f,  0.1707430204f,
                                                        0.2327233347f,  0.3562490486f};

// The atmosphere: scale heights of air (Rayleigh) and aerosols (Mie), m; the aerosols' scattering coefficient
// (m^-1; extinction 1.11 times it) and Henyey–Greenstein-like anisotropy; the radii of the Earth and of the top
// of the atmosphere, m.
constexpr float kRayleighScaleHeight = 8e3f;
constexpr float kMieScaleHeight = 1.2e3f;
constexpr float kMieScattering = 2e-5f;
constexpr float kMieExtinctionRatio = 1.11f;
constexpr float kMieAnisotropy = 0.76f;
constexpr float kEarthRadius = 6360e3f;
constexpr float kAtmosphereRadius = 6420e3f;

}  // namespace ps::sky_data
