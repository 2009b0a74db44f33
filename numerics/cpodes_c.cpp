#include "numerics/cpodes_c.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <sstream>

namespace armsim {
namespace cpodes {

namespace {

double* dataOf(NVector v) { return ArrayVector::updData(v); }
long sizeOf(NVector v) { return ArrayVector::getSize(v); }

// The arithmetic of nvector_SimTK.cpp, loop for loop.
void space(NVector v, long* lrw, long* liw) {
    *lrw = sizeOf(v);
    *liw = 1;
}
double* getArrayPointer(NVector v) { return dataOf(v); }
void linearSum(double a, NVector x, double b, NVector y, NVector z) {
    const double *xp = dataOf(x), *yp = dataOf(y);
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(x); i < n; ++i) zp[i] = a * xp[i] + b * yp[i];
}
void setConst(double c, NVector z) {
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(z); i < n; ++i) zp[i] = c;
}
void prod(NVector x, NVector y, NVector z) {
    const double *xp = dataOf(x), *yp = dataOf(y);
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(x); i < n; ++i) zp[i] = xp[i] * yp[i];
}
void divide(NVector x, NVector y, NVector z) {
    const double *xp = dataOf(x), *yp = dataOf(y);
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(x); i < n; ++i) zp[i] = xp[i] / yp[i];
}
void scale(double c, NVector x, NVector z) {
    const double* xp = dataOf(x);
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(x); i < n; ++i) zp[i] = c * xp[i];
}
void absolute(NVector x, NVector z) {
    const double* xp = dataOf(x);
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(x); i < n; ++i) zp[i] = std::abs(xp[i]);
}
void inv(NVector x, NVector z) {
    const double* xp = dataOf(x);
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(x); i < n; ++i) zp[i] = 1 / xp[i];
}
void addConst(NVector x, double b, NVector z) {
    const double* xp = dataOf(x);
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(x); i < n; ++i) zp[i] = xp[i] + b;
}
double dotProd(NVector x, NVector y) {
    const double *xp = dataOf(x), *yp = dataOf(y);
    double sum = 0;
    for (long i = 0, n = sizeOf(x); i < n; ++i) sum += xp[i] * yp[i];
    return sum;
}
double maxNorm(NVector x) {
    const double* xp = dataOf(x);
    double m = std::abs(xp[0]);
    for (long i = 1, n = sizeOf(x); i < n; ++i) {
        const double a = std::abs(xp[i]);
        if (a > m) m = a;
    }
    return m;
}
double wrmsNorm(NVector x, NVector w) {
    const double *xp = dataOf(x), *wp = dataOf(w);
    const int n = int(sizeOf(x));
    double sumsq = 0;
    for (int i = 0; i < n; ++i) {
        const double xw = xp[i] * wp[i];
        sumsq += xw * xw;
    }
    return std::sqrt(sumsq / n);
}
double wrmsNormMask(NVector x, NVector w, NVector id) {
    const double *xp = dataOf(x), *wp = dataOf(w), *idp = dataOf(id);
    const int n = int(sizeOf(x));
    double sumsq = 0;
    for (int i = 0; i < n; ++i)
        if (idp[i] != 0) {
            const double xw = xp[i] * wp[i];
            sumsq += xw * xw;
        }
    return std::sqrt(sumsq / n);
}
double minimum(NVector x) {
    const double* xp = dataOf(x);
    double m = xp[0];
    for (long i = 1, n = sizeOf(x); i < n; ++i)
        if (xp[i] < m) m = xp[i];
    return m;
}
double wl2Norm(NVector x, NVector w) {
    const double *xp = dataOf(x), *wp = dataOf(w);
    double sumsq = 0;
    for (long i = 0, n = sizeOf(x); i < n; ++i) {
        const double xw = xp[i] * wp[i];
        sumsq += xw * xw;
    }
    return std::sqrt(sumsq);
}
double l1Norm(NVector x) {
    const double* xp = dataOf(x);
    double sum = 0;
    for (long i = 0, n = sizeOf(x); i < n; ++i) sum += std::abs(xp[i]);
    return sum;
}
void compare(double c, NVector x, NVector z) {
    const double* xp = dataOf(x);
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(x); i < n; ++i) zp[i] = std::abs(xp[i]) >= c ? 1 : 0;
}
booleantype invTest(NVector x, NVector z) {
    const double* xp = dataOf(x);
    double* zp = dataOf(z);
    for (long i = 0, n = sizeOf(x); i < n; ++i) {
        if (xp[i] == 0) return 0;
        zp[i] = 1 / xp[i];
    }
    return 1;
}
booleantype constrMask(NVector c, NVector x, NVector m) {
    const double *cp = dataOf(c), *xp = dataOf(x);
    double* mp = dataOf(m);
    const long n = sizeOf(x);
    for (long i = 0; i < n; ++i) mp[i] = 0;
    booleantype allGood = 1;
    for (long i = 0; i < n; ++i) {
        if (cp[i] == 0) continue;
        if (cp[i] == 2 && xp[i] > 0) continue;
        if (cp[i] == 1 && xp[i] >= 0) continue;
        if (cp[i] == -1 && xp[i] <= 0) continue;
        if (cp[i] == -2 && xp[i] < 0) continue;
        mp[i] = 1;
        allGood = 0;
    }
    return allGood;
}
double minQuotient(NVector num, NVector denom) {
    const double *np = dataOf(num), *dp = dataOf(denom);
    double result = DBL_MAX;  // BIG_REAL
    for (long i = 0, n = sizeOf(num); i < n; ++i) {
        if (dp[i] == 0) continue;
        const double q = np[i] / dp[i];
        if (q < result) result = q;
    }
    return result;
}

}  // namespace

NVectorOps ArrayVector::makeOps() {
    NVectorOps o{};
    o.nvclone = clone;
    o.nvcloneempty = cloneEmpty;
    o.nvdestroy = destroy;
    o.nvspace = space;
    o.nvgetarraypointer = getArrayPointer;
    o.nvsetarraypointer = setArrayPointer;
    o.nvlinearsum = linearSum;
    o.nvconst = setConst;
    o.nvprod = prod;
    o.nvdiv = divide;
    o.nvscale = scale;
    o.nvabs = absolute;
    o.nvinv = inv;
    o.nvaddconst = addConst;
    o.nvdotprod = dotProd;
    o.nvmaxnorm = maxNorm;
    o.nvwrmsnorm = wrmsNorm;
    o.nvwrmsnormmask = wrmsNormMask;
    o.nvmin = minimum;
    o.nvwl2norm = wl2Norm;
    o.nvl1norm = l1Norm;
    o.nvcompare = compare;
    o.nvinvtest = invTest;
    o.nvconstrmask = constrMask;
    o.nvminquotient = minQuotient;
    return o;
}

ArrayVector::ArrayVector(long size, double* data) : size_(size), data_(data) {
    static NVectorOps ops = makeOps();  // CPODES wants a non-const table; nothing writes it
    content = this;
    this->ops = &ops;
}

ArrayVector::~ArrayVector() { delete[] owned_; }

NVector ArrayVector::clone(NVector w) {  // as N_Vector_SimTK: a copy, values included
    const long n = sizeOf(w);
    auto* v = new ArrayVector(n, new double[std::size_t(n)]);
    v->owned_ = v->data_;
    if (dataOf(w)) std::copy(dataOf(w), dataOf(w) + n, v->data_);
    return v;
}

NVector ArrayVector::cloneEmpty(NVector w) { return new ArrayVector(sizeOf(w), nullptr); }

void ArrayVector::destroy(NVector v) { delete static_cast<ArrayVector*>(v); }

void ArrayVector::setArrayPointer(double* data, NVector v) { static_cast<ArrayVector*>(v)->data_ = data; }

std::string findCpodesLayoutMismatch() {
    std::ostringstream out;
    NVector v = N_VNew_Serial(3);
    if (!v) return "N_VNew_Serial(3) returned null";
    const NVectorOps& o = *v->ops;
    auto slot = [&](const char* name, auto have, auto want) {
        if (reinterpret_cast<const void*>(have) != reinterpret_cast<const void*>(want))
            out << "ops slot " << name << " does not hold its N_V*_Serial function; ";
    };
    slot("nvclone", o.nvclone, &N_VClone_Serial);
    slot("nvcloneempty", o.nvcloneempty, &N_VCloneEmpty_Serial);
    slot("nvdestroy", o.nvdestroy, &N_VDestroy_Serial);
    slot("nvspace", o.nvspace, &N_VSpace_Serial);
    slot("nvgetarraypointer", o.nvgetarraypointer, &N_VGetArrayPointer_Serial);
    slot("nvsetarraypointer", o.nvsetarraypointer, &N_VSetArrayPointer_Serial);
    slot("nvlinearsum", o.nvlinearsum, &N_VLinearSum_Serial);
    slot("nvconst", o.nvconst, &N_VConst_Serial);
    slot("nvprod", o.nvprod, &N_VProd_Serial);
    slot("nvdiv", o.nvdiv, &N_VDiv_Serial);
    slot("nvscale", o.nvscale, &N_VScale_Serial);
    slot("nvabs", o.nvabs, &N_VAbs_Serial);
    slot("nvinv", o.nvinv, &N_VInv_Serial);
    slot("nvaddconst", o.nvaddconst, &N_VAddConst_Serial);
    slot("nvdotprod", o.nvdotprod, &N_VDotProd_Serial);
    slot("nvmaxnorm", o.nvmaxnorm, &N_VMaxNorm_Serial);
    slot("nvwrmsnorm", o.nvwrmsnorm, &N_VWrmsNorm_Serial);
    slot("nvwrmsnormmask", o.nvwrmsnormmask, &N_VWrmsNormMask_Serial);
    slot("nvmin", o.nvmin, &N_VMin_Serial);
    slot("nvwl2norm", o.nvwl2norm, &N_VWL2Norm_Serial);
    slot("nvl1norm", o.nvl1norm, &N_VL1Norm_Serial);
    slot("nvcompare", o.nvcompare, &N_VCompare_Serial);
    slot("nvinvtest", o.nvinvtest, &N_VInvTest_Serial);
    slot("nvconstrmask", o.nvconstrmask, &N_VConstrMask_Serial);
    slot("nvminquotient", o.nvminquotient, &N_VMinQuotient_Serial);
    const auto* c = static_cast<const SerialContent*>(v->content);
    if (c->length != 3 || c->own_data != 1 || c->data != N_VGetArrayPointer_Serial(v))
        out << "serial content {length, own_data, data} not as declared; ";
    N_VDestroy_Serial(v);
    auto report = [&out] {
        std::string r = out.str();
        if (r.size() >= 2) r.resize(r.size() - 2);  // the last "; "
        return r;
    };
    if (!out.str().empty()) return report();

    // The library's dispatchers on armsim's vectors: they must reach the slots declared here.
    double xd[3] = {1, 2, 3}, wd[3] = {1, 1, 1}, zd[3] = {0, 0, 0};
    ArrayVector x(3, xd), w(3, wd), z(3, zd);
    if (N_VWrmsNorm(&x, &w) != std::sqrt(14.0 / 3)) out << "N_VWrmsNorm did not dispatch to nvwrmsnorm; ";
    N_VLinearSum(2, &x, -1, &w, &z);
    if (zd[0] != 1 || zd[1] != 3 || zd[2] != 5) out << "N_VLinearSum did not dispatch to nvlinearsum; ";
    return report();
}

}  // namespace cpodes
}  // namespace armsim
