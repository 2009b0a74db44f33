// The C API of CPODES (SUNDIALS 2.3.0 as vendored in Simbody 3.7's libSimTKmath), which Simbody
// exports but does not install headers for. Only what numerics/stiff_ode.cpp uses is declared, after
// simbody/simbody tag Simbody-3.7, SimTKmath/Integrators/src/CPodes/sundials/include/:
// sundials/sundials_nvector.h (N_Vector and its ops table), sundials/sundials_types.h (realtype =
// double, booleantype = int), cpodes/cpodes.h (constants, CPode*), cpodes/cpodes_lapack_exports.h
// (CPLapackDense), nvector/nvector_serial.h (the library's own serial vector, used only to check the
// layout: findCpodesLayoutMismatch).
//
// Private to armsim_muscles. The types live in armsim::cpodes (not the global names SUNDIALS uses) so
// that they cannot collide with another SUNDIALS' headers; C linkage ignores the namespace.
#pragma once

#include <string>

namespace armsim {
namespace cpodes {

struct NVectorOps;
/// struct _generic_N_Vector.
struct NVectorBase {
    void* content;
    NVectorOps* ops;
};
using NVector = NVectorBase*;
using booleantype = int;

/// struct _generic_N_Vector_Ops, in its order.
struct NVectorOps {
    NVector (*nvclone)(NVector);
    NVector (*nvcloneempty)(NVector);
    void (*nvdestroy)(NVector);
    void (*nvspace)(NVector, long*, long*);
    double* (*nvgetarraypointer)(NVector);
    void (*nvsetarraypointer)(double*, NVector);
    void (*nvlinearsum)(double, NVector, double, NVector, NVector);
    void (*nvconst)(double, NVector);
    void (*nvprod)(NVector, NVector, NVector);
    void (*nvdiv)(NVector, NVector, NVector);
    void (*nvscale)(double, NVector, NVector);
    void (*nvabs)(NVector, NVector);
    void (*nvinv)(NVector, NVector);
    void (*nvaddconst)(NVector, double, NVector);
    double (*nvdotprod)(NVector, NVector);
    double (*nvmaxnorm)(NVector);
    double (*nvwrmsnorm)(NVector, NVector);
    double (*nvwrmsnormmask)(NVector, NVector, NVector);
    double (*nvmin)(NVector);
    double (*nvwl2norm)(NVector, NVector);
    double (*nvl1norm)(NVector);
    void (*nvcompare)(double, NVector, NVector);
    booleantype (*nvinvtest)(NVector, NVector);
    booleantype (*nvconstrmask)(NVector, NVector, NVector);
    double (*nvminquotient)(NVector, NVector);
};

/// struct _N_VectorContent_Serial.
struct SerialContent {
    long length;
    booleantype own_data;
    double* data;
};

/// struct _DlsMat (sundials_direct.h): a band matrix's entry (i, j) is cols[j][i - j + s_mu].
struct DlsMatBase {
    int type, M, N, ldim, mu, ml, s_mu;
    double* data;
    int ldata;
    double** cols;
};
using DlsMat = DlsMatBase*;

// cpodes.h
constexpr int CP_BDF = 2, CP_NEWTON = 2, CP_EXPL = 1, CP_SS = 1, CP_ONE_STEP = 2;
constexpr int CP_SUCCESS = 0, CP_TOO_CLOSE = -27;

using CPRhsFn = int (*)(double t, NVector y, NVector fout, void* f_data);
using CPErrHandlerFn = void (*)(int error_code, const char* module, const char* function, char* msg, void* eh_data);

extern "C" {
void* CPodeCreate(int ode_type, int lmm_type, int nls_type);
void CPodeFree(void** cpode_mem);
int CPodeInit(void* cpode_mem, void* fun, void* f_data, double t0, NVector y0, NVector yp0, int tol_type,
              double reltol, void* abstol);
int CPodeSetErrHandlerFn(void* cpode_mem, CPErrHandlerFn ehfun, void* eh_data);
int CPodeSetMinStep(void* cpode_mem, double hmin);
int CPodeSetMaxStep(void* cpode_mem, double hmax);
int CPodeSetNonlinConvCoef(void* cpode_mem, double nlscoef);
int CPLapackDense(void* cpode_mem, int N);
int CPLapackBand(void* cpode_mem, int N, int mupper, int mlower);
/// jac: with CPLapackBand a CPDlsBandJacExplFn, int(int N, int mupper, int mlower, double t, NVector y,
/// NVector fy, DlsMat J, void* jac_data, NVector tmp1, NVector tmp2, NVector tmp3); with CPLapackDense a
/// CPDlsDenseJacExplFn, the same without mupper and mlower.
int CPDlsSetJacFn(void* cpode_mem, void* jac, void* jac_data);
int CPode(void* cpode_mem, double tout, double* tret, NVector yout, NVector ypout, int mode);
int CPodeGetDky(void* cpode_mem, double t, int k, NVector dky);
int CPodeGetNumSteps(void* cpode_mem, long* nsteps);
int CPodeGetCurrentStep(void* cpode_mem, double* hcur);
int CPodeGetErrWeights(void* cpode_mem, NVector eweight);

// cpodes_spgmr.h, cpodes_spils.h, sundials_iterative.h: the Krylov solver with a user preconditioner.
constexpr int PREC_LEFT = 1;
using CPSpilsPrecSetupExplFn = int (*)(double t, NVector y, NVector fy, booleantype jok, booleantype* jcurPtr,
                                       double gamma, void* P_data, NVector tmp1, NVector tmp2, NVector tmp3);
using CPSpilsPrecSolveExplFn = int (*)(double t, NVector y, NVector fy, NVector b, NVector x, double gamma,
                                       double delta, int lr, void* P_data, NVector tmp);
using CPSpilsJacTimesVecExplFn = int (*)(double t, NVector y, NVector fy, NVector v, NVector Jv, void* jac_data,
                                         NVector tmp);
int CPSpgmr(void* cpode_mem, int pretype, int maxl);
int CPSpilsGetNumLinIters(void* cpode_mem, long* nliters);
int CPodeGetNumNonlinSolvIters(void* cpode_mem, long* nniters);
int CPSpilsSetPreconditioner(void* cpode_mem, void* pset, void* psolve, void* P_data);
int CPSpilsSetJacTimesVecFn(void* cpode_mem, void* jtimes, void* jac_data);

// nvector_serial.h: only for findCpodesLayoutMismatch.
NVector N_VNew_Serial(long vec_length);
void N_VDestroy_Serial(NVector v);
NVector N_VClone_Serial(NVector w);
NVector N_VCloneEmpty_Serial(NVector w);
void N_VSpace_Serial(NVector v, long* lrw, long* liw);
double* N_VGetArrayPointer_Serial(NVector v);
void N_VSetArrayPointer_Serial(double* v_data, NVector v);
void N_VLinearSum_Serial(double a, NVector x, double b, NVector y, NVector z);
void N_VConst_Serial(double c, NVector z);
void N_VProd_Serial(NVector x, NVector y, NVector z);
void N_VDiv_Serial(NVector x, NVector y, NVector z);
void N_VScale_Serial(double c, NVector x, NVector z);
void N_VAbs_Serial(NVector x, NVector z);
void N_VInv_Serial(NVector x, NVector z);
void N_VAddConst_Serial(NVector x, double b, NVector z);
double N_VDotProd_Serial(NVector x, NVector y);
double N_VMaxNorm_Serial(NVector x);
double N_VWrmsNorm_Serial(NVector x, NVector w);
double N_VWrmsNormMask_Serial(NVector x, NVector w, NVector id);
double N_VMin_Serial(NVector x);
double N_VWL2Norm_Serial(NVector x, NVector w);
double N_VL1Norm_Serial(NVector x);
void N_VCompare_Serial(double c, NVector x, NVector z);
booleantype N_VInvTest_Serial(NVector x, NVector z);
booleantype N_VConstrMask_Serial(NVector c, NVector x, NVector m);
double N_VMinQuotient_Serial(NVector num, NVector denom);
// The generic dispatchers (sundials_nvector.c): they call through the ops table.
double N_VWrmsNorm(NVector x, NVector w);
void N_VLinearSum(double a, NVector x, double b, NVector y, NVector z);
}

/// Empty if the layout declared here matches the loaded libSimTKmath (the ops table of the library's
/// own serial vector holds its N_V*_Serial functions in the declared order, its content is where it
/// is declared, and the library's dispatchers read the slots declared here); else what differs.
std::string findCpodesLayoutMismatch();

/// armsim's N_Vector: `size` contiguous doubles, either a view of the caller's array or owned (the
/// clones CPODES makes). Its operations do the arithmetic of Simbody's N_Vector_SimTK
/// (SimTKmath/Integrators/src/CPodes/nvector_SimTK.cpp: z = a x + b y as two products and a sum,
/// norms summed in index order), so CPODES takes the same steps as under CPodesIntegrator, without
/// SimTK::Vector temporaries.
class ArrayVector : public NVectorBase {
public:
    /// A view of data[0 .. size); the caller keeps the array alive.
    ArrayVector(long size, double* data);
    ArrayVector(const ArrayVector&) = delete;
    ArrayVector& operator=(const ArrayVector&) = delete;
    ~ArrayVector();
    static double* updData(NVector v) { return static_cast<ArrayVector*>(v)->data_; }
    static long getSize(NVector v) { return static_cast<ArrayVector*>(v)->size_; }

private:
    static NVector clone(NVector w);
    static NVector cloneEmpty(NVector w);
    static void destroy(NVector v);
    static void setArrayPointer(double* data, NVector v);
    static NVectorOps makeOps();
    long size_;
    double* data_;
    double* owned_ = nullptr;  // what destroy frees (CPODES swaps data_ while building a Jacobian)
};

}  // namespace cpodes
}  // namespace armsim
