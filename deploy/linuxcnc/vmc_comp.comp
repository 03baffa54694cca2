component vmc_comp "Thermal error compensation of a vmc-twin hybrid model in the servo thread";

description """
The glue between LinuxCNC's HAL and the vmc-rtcomp library (libvmc_rtcomp.a, linked in): the
model file named by the module parameter \\fBmodel\\fR is read and compiled when the module is
loaded (outside the servo thread); every period the function then solves the compensation of
the commanded position under the latest sensor sample, without allocation or lock.

A sample is taken on a rising edge of \\fBsample\\fR: the readings temp-NN (the first
\\fBsensors\\fR of them, in the model's sensor order), with the spindle speed and axis feeds
averaged over the periods since the previous sample. The component's clock is the sum of the
thread's periods.

Corrections are in mm, to add to the commanded position: \\fBcorr-x/y/z\\fR, and the same in
counts of \\fBcount-mm\\fR for LinuxCNC's external offsets (net counts-x to
axis.x.eoffset-counts, set axis.x.eoffset-scale to count-mm).
""";

pin in float temp-##[32] "Sensor readings, degC, model sensor order (the first 'sensors' are read)";
pin in bit sample "Rising edge: temp-NN hold a new sensor sample";
pin in float pos-cmd-x "Commanded tool position X, mm, without the corrections";
pin in float pos-cmd-y "Commanded tool position Y, mm, without the corrections";
pin in float pos-cmd-z "Commanded tool position Z, mm, without the corrections";
pin in float spindle-speed-rpm "Commanded spindle speed, rpm";
pin in float feed-x "Commanded X axis speed, mm/min (|v| is used)";
pin in float feed-y "Commanded Y axis speed, mm/min (|v| is used)";
pin in float feed-z "Commanded Z axis speed, mm/min (|v| is used)";
pin in float count-mm = 0.000001 "Size of one count of counts-x/y/z, mm";
pin out float corr-x "Correction to add to X, mm";
pin out float corr-y "Correction to add to Y, mm";
pin out float corr-z "Correction to add to Z, mm";
pin out s32 counts-x "corr-x in counts of count-mm (for axis.x.eoffset-counts)";
pin out s32 counts-y "corr-y in counts of count-mm (for axis.y.eoffset-counts)";
pin out s32 counts-z "corr-z in counts of count-mm (for axis.z.eoffset-counts)";
pin out s32 state "Status of the period: 0 ok, 1 not converged, 2 no sample yet, 3 prediction not finite, -1 bad input";
pin out s32 solve-iters "Predictor evaluations of the period's fixed point";
pin out u32 sensors "Number of sensors the model reads";
pin out u32 samples "Samples taken";
pin out float clock-s "The component's clock, s (sum of the periods)";
pin out float sample-clock-s "Clock of the latest sample, s";

variable int last_sample_bit;
variable double clock_acc_s;
variable hal_u32_t model_sensors;

modparam dummy model "Path of the model file (the JSON vmc-twin train writes); read at load time";

/* No initialisers on the variables: halcompile applies them after extra_setup; the state is
   zeroed memory. */
option extra_setup yes;
option extra_cleanup yes;

function _ "One servo period: sample on a rising edge of 'sample', then the corrections";

license "MIT";
author "vmc-twin";
include <stdio.h>;
include <stdlib.h>;
include "vmc_rtcomp.h";
;;

/* The model file's path (a string module parameter: halcompile's modparam knows int only). */
static char *model = 0;
RTAPI_MP_STRING(model, "Path of the model file (the JSON vmc-twin train writes)");

/* One handle per instance, in instance order (at most 64 instances). */
#define VMC_MAX_INSTANCES 64
static int vmc_n_handles = 0;
static VmcComp *vmc_handle_of[VMC_MAX_INSTANCES];
static struct __comp_state *vmc_inst_of[VMC_MAX_INSTANCES];

/* The handle of an instance (looked up by its state pointer: no allocation, no lock). */
static VmcComp *vmc_handle(struct __comp_state *inst) {
    int k;
    for (k = 0; k < vmc_n_handles; k++) {
        if (vmc_inst_of[k] == inst) return vmc_handle_of[k];
    }
    return 0;
}

/* Reads the model file and compiles it: at load time, outside the servo thread. */
EXTRA_SETUP() {
    FILE *f;
    long size;
    uint8_t *text;
    char err[512];
    VmcComp *h;
    size_t n, k;
    (void)prefix;
    (void)extra_arg;
    if (vmc_n_handles >= VMC_MAX_INSTANCES) {
        rtapi_print_msg(RTAPI_MSG_ERR, "vmc_comp: more than %d instances\n", VMC_MAX_INSTANCES);
        return -EINVAL;
    }
    if (!model || !model[0]) {
        rtapi_print_msg(RTAPI_MSG_ERR, "vmc_comp: no model file (loadrt vmc_comp model=PATH)\n");
        return -EINVAL;
    }
    f = fopen(model, "rb");
    if (!f) {
        rtapi_print_msg(RTAPI_MSG_ERR, "vmc_comp: cannot open the model file %s\n", model);
        return -ENOENT;
    }
    if (fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        rtapi_print_msg(RTAPI_MSG_ERR, "vmc_comp: cannot read the model file %s\n", model);
        return -EIO;
    }
    text = malloc(size > 0 ? (size_t)size : 1);
    if (!text) {
        fclose(f);
        return -ENOMEM;
    }
    n = fread(text, 1, (size_t)size, f);
    fclose(f);
    if (n != (size_t)size) {
        free(text);
        rtapi_print_msg(RTAPI_MSG_ERR, "vmc_comp: short read of the model file %s\n", model);
        return -EIO;
    }
    h = vmc_comp_new_err(text, n, err, sizeof err);
    free(text);
    if (!h) {
        rtapi_print_msg(RTAPI_MSG_ERR, "vmc_comp: the model file %s cannot be used: %s\n", model, err);
        return -EINVAL;
    }
    k = vmc_comp_n_sensors(h);
    if (k > 32) {
        vmc_comp_free(h);
        rtapi_print_msg(RTAPI_MSG_ERR, "vmc_comp: the model reads %zu sensors; at most 32 pins\n", k);
        return -EINVAL;
    }
    vmc_handle_of[vmc_n_handles] = h;
    vmc_inst_of[vmc_n_handles] = __comp_inst;
    vmc_n_handles++;
    /* The pins do not exist yet (extra_setup runs first): the function shows the count. */
    model_sensors = (hal_u32_t)k;
    rtapi_print_msg(RTAPI_MSG_INFO, "vmc_comp: %s: model %s, %zu sensors\n", prefix, model, k);
    return 0;
}

EXTRA_CLEANUP() {
    int k;
    for (k = 0; k < vmc_n_handles; k++) {
        vmc_comp_free(vmc_handle_of[k]);
        vmc_handle_of[k] = 0;
    }
    vmc_n_handles = 0;
}

FUNCTION(_) {
    VmcComp *h = vmc_handle(__comp_inst);
    double readings[32];
    VmcCompInputs in;
    VmcCompOutputs out;
    int rising = sample && !last_sample_bit;
    size_t n = h ? vmc_comp_n_sensors(h) : 0;
    size_t k;
    last_sample_bit = sample;
    sensors = model_sensors;
    clock_acc_s += fperiod;
    clock_s = clock_acc_s;
    for (k = 0; k < n && k < 32; k++) readings[k] = temp(k);
    in.temps_degc = readings;
    in.n_temps = n;
    in.time_s = clock_acc_s;
    in.commanded_mm[0] = pos_cmd_x;
    in.commanded_mm[1] = pos_cmd_y;
    in.commanded_mm[2] = pos_cmd_z;
    in.spindle_rpm = spindle_speed_rpm;
    in.axis_feed_mm_per_min[0] = feed_x;
    in.axis_feed_mm_per_min[1] = feed_y;
    in.axis_feed_mm_per_min[2] = feed_z;
    in.new_sample = rising;
    state = vmc_comp_update(h, &in, &out);
    if (rising && state != VMC_COMP_BAD_INPUT) {
        samples = samples + 1;
        sample_clock_s = clock_acc_s;
    }
    corr_x = out.correction_mm[0];
    corr_y = out.correction_mm[1];
    corr_z = out.correction_mm[2];
    solve_iters = out.iterations;
    if (count_mm > 0.0) {
        /* Rounded to the nearest count; |corr| is far below the s32 range at any sane count. */
        counts_x = (hal_s32_t)(corr_x / count_mm + (corr_x >= 0.0 ? 0.5 : -0.5));
        counts_y = (hal_s32_t)(corr_y / count_mm + (corr_y >= 0.0 ? 0.5 : -0.5));
        counts_z = (hal_s32_t)(corr_z / count_mm + (corr_z >= 0.0 ? 0.5 : -0.5));
    } else {
        counts_x = counts_y = counts_z = 0;
    }
}
