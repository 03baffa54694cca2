/*
 * vmc_rtcomp.h — the compiled hybrid thermal-error model behind a C ABI, for a controller's
 * real-time thread (a LinuxCNC HAL component first). The library: crates/vmc-rtcomp
 * (static library libvmc_rtcomp.a).
 *
 * Every servo period the controller passes its clock, the commanded tool position, the
 * commanded spindle speed and axis speeds, and — when its sensors have a new sample — the
 * temperature readings; the component returns per-axis corrections to add to the commanded
 * position (in LinuxCNC: through the axes' external offsets).
 *
 * Units: s, degrees Celsius, mm, rpm, mm/min.
 *
 * Threads and memory: vmc_comp_new / vmc_comp_new_err allocate (call them at load time);
 * vmc_comp_update, vmc_comp_n_sensors, vmc_comp_sensor_name and vmc_comp_set_tool_offset
 * neither allocate nor lock; vmc_comp_free deallocates (at unload). A handle is used by one
 * thread at a time.
 */
#ifndef VMC_RTCOMP_H
#define VMC_RTCOMP_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Status of a period (the return value of vmc_comp_update and VmcCompOutputs.status). */
#define VMC_COMP_OK 0             /* corrections computed */
#define VMC_COMP_NOT_CONVERGED 1  /* fixed point hit its evaluation cap; corrections of its last iterate */
#define VMC_COMP_NO_READINGS 2    /* no sample yet: zero corrections */
#define VMC_COMP_NOT_FINITE 3     /* prediction not a number (e.g. a failed sensor): zero corrections */
#define VMC_COMP_BAD_INPUT (-1)   /* null pointer, wrong n_temps, non-finite input: zero corrections, nothing taken */

/* The component (opaque). */
typedef struct VmcComp VmcComp;

/* What the controller gives every servo period. */
typedef struct {
    const double *temps_degc;        /* the readings, model sensor order; read only when new_sample != 0 */
    size_t n_temps;                  /* number of readings (must equal vmc_comp_n_sensors) */
    double time_s;                   /* the controller's clock, s, increasing */
    double commanded_mm[3];          /* commanded tool position X, Y, Z (workpiece coordinates), without the corrections */
    double spindle_rpm;              /* commanded spindle speed now (0 when stopped) */
    double axis_feed_mm_per_min[3];  /* commanded axis speeds now, X, Y, Z (|v| is used) */
    int32_t new_sample;              /* nonzero: temps_degc is a new sensor sample */
} VmcCompInputs;

/* What the component gives back every servo period. */
typedef struct {
    double correction_mm[3];  /* add to the commanded X, Y, Z (compensated command − commanded) */
    double last_step_mm;      /* size of the fixed point's last step */
    int32_t iterations;       /* predictor evaluations of the fixed point */
    int32_t status;           /* VMC_COMP_* */
} VmcCompOutputs;

/* Loads the model file text (the JSON `train` writes; `len` bytes, no NUL needed).
   Returns a handle, or NULL when the text cannot be used (not a model file, not a hybrid
   model, ...). */
VmcComp *vmc_comp_new(const uint8_t *json, size_t len);

/* As vmc_comp_new; on failure also writes the reason, NUL-terminated and cut to fit, into
   err (err_cap bytes; nothing written when err is NULL or err_cap is 0). */
VmcComp *vmc_comp_new_err(const uint8_t *json, size_t len, char *err, size_t err_cap);

/* One servo period: takes the sample when inputs->new_sample is nonzero (readings, and the
   spindle speed and axis speeds averaged over the periods since the previous sample), solves
   the compensation for inputs->commanded_mm, writes *outputs (when not NULL) and returns the
   status. */
int32_t vmc_comp_update(VmcComp *comp, const VmcCompInputs *inputs, VmcCompOutputs *outputs);

/* Number of sensors the model reads; 0 for NULL. */
size_t vmc_comp_n_sensors(const VmcComp *comp);

/* Name of sensor `index` (model order), owned by the handle; NULL out of range. */
const char *vmc_comp_sensor_name(const VmcComp *comp, size_t index);

/* Tool change: tool tip from the spindle gauge point, mm, spindle frame (a vertical mill:
   0, 0, -gauge length). VMC_COMP_OK or VMC_COMP_BAD_INPUT (NULL handle, non-finite value). */
int32_t vmc_comp_set_tool_offset(VmcComp *comp, double x_mm, double y_mm, double z_mm);

/* Releases a handle (NULL: nothing). */
void vmc_comp_free(VmcComp *comp);

#ifdef __cplusplus
}
#endif

#endif /* VMC_RTCOMP_H */
