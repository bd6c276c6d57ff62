// Dumps what MuJoCo 3.x (the official WebAssembly build, npm package mujoco-js) compiles from MJCF
// files and how it simulates them, as JSON, for tests/mjcf/reference3x_test.cc to compare with
// URLab's dialect bridge on MuJoCo 2.2.2.
//
//   node dump3x.mjs JOB.json > out.json
//
// JOB.json: {"module": ".../mujoco-js/dist/mujoco_wasm.js", "steps": 500, "record_every": 25,
//            (a model may add "extended": true for passive forces and sensors, see dump, and
//            "weld_diag_as_222": true, see below),
//            "probe": true, "probe_act_steps": 20, "strip": [{"element": "gyro", "attribute": "nsample"}, ...],
//            "models": [{"id": "arm_servos", "file": "/abs/dir/arm_servos.xml"}, ...]}
//
// Each model's folder is copied (recursively, files only up to 8 MiB) into the module's virtual
// file system, so includes and asset files resolve as on disk. `strip` removes attributes the
// reference's MuJoCo version does not know (newer than it) from every copied .xml file, and
// `add` ({"element", "attribute", "value", "if_present"}) writes out defaults that version gets
// wrong; the test keeps both lists and says why each entry is there.
//
// Output: {"version": "3.3.8", "models": {"<id>": {"error": "..."} | {"data": DUMP}}}, where DUMP
// is category -> entity -> field -> number[] | string (see `dump` below); reference3x_test.cc
// builds the same structure from MuJoCo 2.2.2 and compares field by field, entities by name.
import fs from 'node:fs';
import path from 'node:path';
import {pathToFileURL} from 'node:url';

const job = JSON.parse(fs.readFileSync(process.argv[2], 'utf8'));
const printed = [];
const loadMujoco = (await import(pathToFileURL(job.module).href)).default;
const mj = await loadMujoco({print: (s) => printed.push(s), printErr: (s) => printed.push(s)});

// The module exports no heap view; any typed array of a model is a view on the wasm memory, which
// is how the message of a C++ exception (mjXError holds `char message[1000]` first) is read.
mj.FS.writeFile('/empty.xml', '<mujoco/>');
const heapModel = mj.MjModel.loadFromXML('/empty.xml');
function exceptionText(e) {
  if (!e || typeof e.excPtr !== 'number') return String(e && e.message ? e.message : e);
  const mem = new Uint8Array(heapModel.body_mass.buffer);
  let end = e.excPtr;
  while (end < mem.length && mem[end] !== 0 && end - e.excPtr < 1000) end++;
  return `${e.name || 'exception'}: ${new TextDecoder().decode(mem.subarray(e.excPtr, end)).trim()}`;
}

const attrPattern = (name) => new RegExp(`\\s${name}\\s*=\\s*("[^"]*"|'[^']*')`, 'g');

// The reference's copy of an .xml file: `strip` rules remove attributes, `add` rules add
// attribute="value" to elements that have `if_present` and lack the attribute.
function adaptXml(text) {
  for (const {element, attribute} of job.strip || []) {
    const tag = new RegExp(`<${element}\\b[^>]*>`, 'g');
    text = text.replace(tag, (t) => t.replace(attrPattern(attribute), ''));
  }
  for (const {element, attribute, value, if_present: ifPresent} of job.add || []) {
    const tag = new RegExp(`<${element}\\b[^>]*>`, 'g');
    text = text.replace(tag, (t) => {
      if (t.search(attrPattern(ifPresent)) < 0 || t.search(attrPattern(attribute)) >= 0) return t;
      return t.replace(new RegExp(`^<${element}\\b`), `<${element} ${attribute}="${value}"`);
    });
  }
  return text;
}

function copyTree(src, dst) {
  mj.FS.mkdirTree(dst);
  for (const e of fs.readdirSync(src, {withFileTypes: true})) {
    const s = path.join(src, e.name);
    const d = `${dst}/${e.name}`;
    if (e.isDirectory()) {
      copyTree(s, d);
    } else if (e.isFile() && fs.statSync(s).size <= 8 << 20) {
      if (s.endsWith('.xml')) {
        mj.FS.writeFile(d, adaptXml(fs.readFileSync(s, 'utf8')));
      } else {
        mj.FS.writeFile(d, fs.readFileSync(s));
      }
    }
  }
}

// Enum value -> lower-case name without the prefix (mjtDyn.mjDYN_FILTEREXACT -> "filterexact").
function enumNames(enumObj, prefix) {
  const out = {};
  for (const [k, v] of Object.entries(enumObj)) {
    if (k.startsWith(prefix) && v && typeof v.value === 'number') {
      out[v.value] = k.slice(prefix.length).toLowerCase();
    }
  }
  return out;
}
const E = {
  joint: enumNames(mj.mjtJoint, 'mjJNT_'),
  geom: enumNames(mj.mjtGeom, 'mjGEOM_'),
  trn: enumNames(mj.mjtTrn, 'mjTRN_'),
  dyn: enumNames(mj.mjtDyn, 'mjDYN_'),
  gain: enumNames(mj.mjtGain, 'mjGAIN_'),
  bias: enumNames(mj.mjtBias, 'mjBIAS_'),
  integrator: enumNames(mj.mjtIntegrator, 'mjINT_'),
  cone: enumNames(mj.mjtCone, 'mjCONE_'),
  solver: enumNames(mj.mjtSolver, 'mjSOL_'),
  eq: enumNames(mj.mjtEq, 'mjEQ_'),
};
const OBJ = {};
for (const [k, v] of Object.entries(mj.mjtObj)) if (v && typeof v.value === 'number') OBJ[k] = v.value;

const slice = (arr, i, n) => Array.from(arr.subarray(i * n, (i + 1) * n));

// Full inertia tensor (xx yy zz xy xz yz) in the body frame from principal moments + iquat: does
// not depend on how principal axes were ordered or signed.
function inertiaTensor(diag, q) {
  const [w, x, y, z] = q;
  const R = [
    [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
    [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
    [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
  ];
  const I = (a, b) => R[a][0] * diag[0] * R[b][0] + R[a][1] * diag[1] * R[b][1] +
      R[a][2] * diag[2] * R[b][2];
  return [I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)];
}

// Element names read from the model's name table (mj_id2name's binding returns stray text
// for unnamed elements).
const NAME_ADR = {
  mjOBJ_BODY: 'name_bodyadr', mjOBJ_JOINT: 'name_jntadr', mjOBJ_GEOM: 'name_geomadr',
  mjOBJ_SITE: 'name_siteadr', mjOBJ_CAMERA: 'name_camadr', mjOBJ_LIGHT: 'name_lightadr',
  mjOBJ_TENDON: 'name_tendonadr', mjOBJ_EQUALITY: 'name_eqadr', mjOBJ_ACTUATOR: 'name_actuatoradr',
  mjOBJ_KEY: 'name_keyadr', mjOBJ_HFIELD: 'name_hfieldadr', mjOBJ_SENSOR: 'name_sensoradr',
};

// Body-frame bounding box (min xyz, max xyz) of a mesh geom's vertices: where the mesh is,
// whatever frame each engine chose for it (the mesh's principal inertia frame).
function meshBox(m, g) {
  const mesh = m.geom_dataid[g];
  const adr = m.mesh_vertadr[mesh];
  const n = m.mesh_vertnum[mesh];
  const [w, x, y, z] = slice(m.geom_quat, g, 4);
  const R = [
    [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
    [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
    [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
  ];
  const p = slice(m.geom_pos, g, 3);
  const box = [Infinity, Infinity, Infinity, -Infinity, -Infinity, -Infinity];
  for (let i = adr; i < adr + n; i++) {
    const v = [m.mesh_vert[3 * i], m.mesh_vert[3 * i + 1], m.mesh_vert[3 * i + 2]];
    for (let a = 0; a < 3; a++) {
      const c = p[a] + R[a][0] * v[0] + R[a][1] * v[1] + R[a][2] * v[2];
      box[a] = Math.min(box[a], c);
      box[a + 3] = Math.max(box[a + 3], c);
    }
  }
  return box;
}

function dump(m, d, opts) {
  const names = m.names;
  const name = (type, i) => {
    const adr = m[NAME_ADR[type]][i];
    let end = adr;
    while (end < names.length && names[end] !== 0) end++;
    return new TextDecoder().decode(new Uint8Array(names.buffer, names.byteOffset + adr, end - adr));
  };
  const bodyName = (b) => (b === 0 ? 'world' : name('mjOBJ_BODY', b) || `body#${b}`);
  // Unnamed elements are keyed by their body and their rank among that body's elements of the
  // same kind, which the bridge preserves.
  const keyed = (type, count, bodyOf) => {
    const rank = new Map();
    const keys = [];
    for (let i = 0; i < count; i++) {
      const b = bodyOf(i);
      const r = rank.get(b) || 0;
      rank.set(b, r + 1);
      keys.push(name(type, i) || `${bodyName(b)}#${r}`);
    }
    return keys;
  };
  const out = {};
  const put = (cat, ent, field, v) => {
    ((out[cat] ||= {})[ent] ||= {})[field] = typeof v === 'string' ? v : Array.from(v);
  };

  for (const k of ['nq', 'nv', 'nu', 'na', 'nbody', 'njnt', 'ngeom', 'nsite', 'ncam', 'nlight',
    'ntendon', 'neq', 'nkey', 'nmesh', 'nhfield', ...(opts.extended ? ['nsensordata'] : [])]) {
    put('size', 'model', k, [m[k]]);
  }

  const o = m.opt;
  for (const k of ['timestep', 'impratio', 'tolerance', 'noslip_tolerance', 'density', 'viscosity',
    'o_margin', 'iterations', 'noslip_iterations']) {
    put('option', 'opt', k, [o[k]]);
  }
  for (const k of ['gravity', 'wind', 'magnetic', 'o_solref', 'o_solimp']) put('option', 'opt', k, o[k]);
  put('option', 'opt', 'integrator', E.integrator[o.integrator]);
  put('option', 'opt', 'cone', E.cone[o.cone]);
  put('option', 'opt', 'solver', E.solver[o.solver]);
  // Flags by name; 2.2.2's single "passive" flag is 3.x's spring and damper together.
  const dis = (bit) => ((o.disableflags & mj.mjtDisableBit[bit].value) ? 'disable' : 'enable');
  const en = (bit) => ((o.enableflags & mj.mjtEnableBit[bit].value) ? 'enable' : 'disable');
  for (const f of ['CONSTRAINT', 'EQUALITY', 'FRICTIONLOSS', 'LIMIT', 'CONTACT', 'GRAVITY',
    'CLAMPCTRL', 'WARMSTART', 'FILTERPARENT', 'ACTUATION', 'REFSAFE', 'SENSOR']) {
    put('flag', 'opt', f.toLowerCase(), dis(`mjDSBL_${f}`));
  }
  const spring = dis('mjDSBL_SPRING');
  const damper = dis('mjDSBL_DAMPER');
  put('flag', 'opt', 'passive', spring === damper ? spring : `spring=${spring},damper=${damper}`);
  for (const f of ['OVERRIDE', 'ENERGY', 'FWDINV', 'MULTICCD']) {
    put('flag', 'opt', f.toLowerCase(), en(`mjENBL_${f}`));
  }

  for (let b = 0; b < m.nbody; b++) {
    const k = bodyName(b);
    put('body', k, 'parent', bodyName(m.body_parentid[b]));
    put('body', k, 'pos', slice(m.body_pos, b, 3));
    put('body', k, 'quat', slice(m.body_quat, b, 4));
    put('body', k, 'mass', [m.body_mass[b]]);
    put('body', k, 'ipos', slice(m.body_ipos, b, 3));
    put('body', k, 'inertia', inertiaTensor(slice(m.body_inertia, b, 3), slice(m.body_iquat, b, 4)));
  }

  const jointKeys = [];
  for (let j = 0; j < m.njnt; j++) {
    const k = name('mjOBJ_JOINT', j) || `${bodyName(m.jnt_bodyid[j])}:joint#${j}`;
    jointKeys.push(k);
    const type = E.joint[m.jnt_type[j]];
    const nq = type === 'free' ? 7 : type === 'ball' ? 4 : 1;
    const nv = type === 'free' ? 6 : type === 'ball' ? 3 : 1;
    const qa = m.jnt_qposadr[j];
    const da = m.jnt_dofadr[j];
    put('joint', k, 'type', type);
    put('joint', k, 'body', bodyName(m.jnt_bodyid[j]));
    put('joint', k, 'limited', [m.jnt_limited[j]]);
    if (m.jnt_limited[j]) put('joint', k, 'range', slice(m.jnt_range, j, 2));
    put('joint', k, 'pos', slice(m.jnt_pos, j, 3));
    put('joint', k, 'axis', slice(m.jnt_axis, j, 3));
    put('joint', k, 'stiffness', [m.jnt_stiffness[j]]);
    put('joint', k, 'margin', [m.jnt_margin[j]]);
    put('joint', k, 'solref', slice(m.jnt_solref, j, 2));
    put('joint', k, 'solimp', slice(m.jnt_solimp, j, 5));
    put('joint', k, 'qpos0', Array.from(m.qpos0.subarray(qa, qa + nq)));
    put('joint', k, 'qpos_spring', Array.from(m.qpos_spring.subarray(qa, qa + nq)));
    put('dof', k, 'armature', Array.from(m.dof_armature.subarray(da, da + nv)));
    put('dof', k, 'damping', Array.from(m.dof_damping.subarray(da, da + nv)));
    put('dof', k, 'frictionloss', Array.from(m.dof_frictionloss.subarray(da, da + nv)));
    put('dof', k, 'M0', Array.from(m.dof_M0.subarray(da, da + nv)));
  }
  const perJoint = (arr, nqOrNv) => {
    const res = {};
    for (let j = 0; j < m.njnt; j++) {
      const type = E.joint[m.jnt_type[j]];
      const adr = nqOrNv === 'q' ? m.jnt_qposadr[j] : m.jnt_dofadr[j];
      const n = nqOrNv === 'q' ? (type === 'free' ? 7 : type === 'ball' ? 4 : 1)
                               : (type === 'free' ? 6 : type === 'ball' ? 3 : 1);
      res[jointKeys[j]] = Array.from(arr.subarray(adr, adr + n));
    }
    return res;
  };

  const geomKeys = keyed('mjOBJ_GEOM', m.ngeom, (i) => m.geom_bodyid[i]);
  for (let g = 0; g < m.ngeom; g++) {
    const k = geomKeys[g];
    put('geom', k, 'type', E.geom[m.geom_type[g]]);
    put('geom', k, 'body', bodyName(m.geom_bodyid[g]));
    put('geom', k, 'size', slice(m.geom_size, g, 3));
    put('geom', k, 'pos', slice(m.geom_pos, g, 3));
    put('geom', k, 'quat', slice(m.geom_quat, g, 4));
    put('geom', k, 'friction', slice(m.geom_friction, g, 3));
    put('geom', k, 'solref', slice(m.geom_solref, g, 2));
    put('geom', k, 'solimp', slice(m.geom_solimp, g, 5));
    put('geom', k, 'solmix', [m.geom_solmix[g]]);
    put('geom', k, 'margin', [m.geom_margin[g]]);
    put('geom', k, 'gap', [m.geom_gap[g]]);
    put('geom', k, 'contype', [m.geom_contype[g]]);
    put('geom', k, 'conaffinity', [m.geom_conaffinity[g]]);
    put('geom', k, 'condim', [m.geom_condim[g]]);
    put('geom', k, 'priority', [m.geom_priority[g]]);
    put('geom', k, 'rbound', [m.geom_rbound[g]]);
    if (E.geom[m.geom_type[g]] === 'mesh') put('geom', k, 'mesh_box', meshBox(m, g));
  }
  for (let h = 0; h < m.nhfield; h++) {
    const k = name('mjOBJ_HFIELD', h) || `hfield#${h}`;
    put('hfield', k, 'size', slice(m.hfield_size, h, 4));
    put('hfield', k, 'grid', [m.hfield_nrow[h], m.hfield_ncol[h]]);
  }
  const siteKeys = keyed('mjOBJ_SITE', m.nsite, (i) => m.site_bodyid[i]);
  for (let s = 0; s < m.nsite; s++) {
    put('site', siteKeys[s], 'body', bodyName(m.site_bodyid[s]));
    put('site', siteKeys[s], 'pos', slice(m.site_pos, s, 3));
    put('site', siteKeys[s], 'quat', slice(m.site_quat, s, 4));
  }
  const camKeys = keyed('mjOBJ_CAMERA', m.ncam, (i) => m.cam_bodyid[i]);
  for (let c = 0; c < m.ncam; c++) {
    put('camera', camKeys[c], 'pos', slice(m.cam_pos, c, 3));
    put('camera', camKeys[c], 'quat', slice(m.cam_quat, c, 4));
    put('camera', camKeys[c], 'fovy', [m.cam_fovy[c]]);
  }
  const lightKeys = keyed('mjOBJ_LIGHT', m.nlight, (i) => m.light_bodyid[i]);
  for (let l = 0; l < m.nlight; l++) {
    put('light', lightKeys[l], 'pos', slice(m.light_pos, l, 3));
    put('light', lightKeys[l], 'dir', slice(m.light_dir, l, 3));
    put('light', lightKeys[l], 'directional',
        [m.light_type[l] === mj.mjtLightType.mjLIGHT_DIRECTIONAL.value ? 1 : 0]);
  }

  for (let t = 0; t < m.ntendon; t++) {
    const k = name('mjOBJ_TENDON', t) || `tendon#${t}`;
    put('tendon', k, 'limited', [m.tendon_limited[t]]);
    if (m.tendon_limited[t]) put('tendon', k, 'range', slice(m.tendon_range, t, 2));
    put('tendon', k, 'stiffness', [m.tendon_stiffness[t]]);
    put('tendon', k, 'damping', [m.tendon_damping[t]]);
    put('tendon', k, 'frictionloss', [m.tendon_frictionloss[t]]);
    put('tendon', k, 'margin', [m.tendon_margin[t]]);
    put('tendon', k, 'length0', [m.tendon_length0[t]]);
  }

  for (let e = 0; e < m.neq; e++) {
    const k = name('mjOBJ_EQUALITY', e) || `equality#${e}`;
    const type = E.eq[m.eq_type[e]];
    put('equality', k, 'type', type);
    put('equality', k, 'active', [m.eq_active0[e]]);
    put('equality', k, 'solref', slice(m.eq_solref, e, 2));
    put('equality', k, 'solimp', slice(m.eq_solimp, e, 5));
    const nd = m.eq_data.length / Math.max(m.neq, 1);
    // joint/tendon: polynomial coefficients; connect: the two anchors.
    put('equality', k, 'data', slice(m.eq_data, e, nd).slice(0, type === 'connect' ? 6 : 5));
  }

  const actKeys = [];
  for (let a = 0; a < m.nu; a++) {
    const k = name('mjOBJ_ACTUATOR', a) || `actuator#${a}`;
    actKeys.push(k);
    put('actuator', k, 'trntype', E.trn[m.actuator_trntype[a]]);
    put('actuator', k, 'dyntype', E.dyn[m.actuator_dyntype[a]]);
    put('actuator', k, 'gaintype', E.gain[m.actuator_gaintype[a]]);
    put('actuator', k, 'biastype', E.bias[m.actuator_biastype[a]]);
    // dynprm/biasprm only where the engine reads them (dyntype/biastype not none).
    if (E.dyn[m.actuator_dyntype[a]] !== 'none') put('actuator', k, 'dynprm', slice(m.actuator_dynprm, a, 10));
    put('actuator', k, 'gainprm', slice(m.actuator_gainprm, a, 10));
    if (E.bias[m.actuator_biastype[a]] !== 'none') put('actuator', k, 'biasprm', slice(m.actuator_biasprm, a, 10));
    put('actuator', k, 'gear', slice(m.actuator_gear, a, 6));
    put('actuator', k, 'ctrllimited', [m.actuator_ctrllimited[a]]);
    put('actuator', k, 'forcelimited', [m.actuator_forcelimited[a]]);
    put('actuator', k, 'actlimited', [m.actuator_actlimited[a]]);
    if (m.actuator_ctrllimited[a]) put('actuator', k, 'ctrlrange', slice(m.actuator_ctrlrange, a, 2));
    if (m.actuator_forcelimited[a]) {
      put('actuator', k, 'forcerange', slice(m.actuator_forcerange, a, 2));
    }
    if (m.actuator_actlimited[a]) put('actuator', k, 'actrange', slice(m.actuator_actrange, a, 2));
    // Not compared: lets the test's known-difference table recognise actuators whose joint or
    // tendon has a 3.x actuatorfrcrange.
    const trn = m.actuator_trnid[2 * a];
    const type = E.trn[m.actuator_trntype[a]];
    const joint = type === 'joint' || type === 'jointinparent';
    const frc = joint ? m.jnt_actfrclimited[trn] : type === 'tendon' ? m.tendon_actfrclimited[trn] : 0;
    put('meta', k, 'target_actfrclimited', frc ? (joint ? 'joint' : 'tendon') : 'none');
  }

  for (let i = 0; i < m.nkey; i++) {
    const k = name('mjOBJ_KEY', i) || `key#${i}`;
    put('key', k, 'time', [m.key_time[i]]);
    const q = m.key_qpos.subarray(i * m.nq, (i + 1) * m.nq);
    const v = m.key_qvel.subarray(i * m.nv, (i + 1) * m.nv);
    for (const [j, vals] of Object.entries(perJoint(q, 'q'))) put('key', `${k}/${j}`, 'qpos', vals);
    for (const [j, vals] of Object.entries(perJoint(v, 'v'))) put('key', `${k}/${j}`, 'qvel', vals);
    for (let a = 0; a < m.nu; a++) {
      put('key', `${k}/${actKeys[a]}`, 'ctrl', [m.key_ctrl[i * m.nu + a]]);
      if (m.actuator_actnum[a] > 0) {
        put('key', `${k}/${actKeys[a]}`, 'act', [m.key_act[i * m.na + m.actuator_actadr[a]]]);
      }
    }
  }

  // Actuation probe: every actuator at the top (then bottom) of its control range (unlimited:
  // +-1), at qpos0 with act = 0: the joint forces after every clamp (qfrc_actuator per dof) and
  // the actuator forces; then, for the top, the activations a few steps later.
  if (opts.probe && m.nu > 0) {
    for (const [label, side] of [['hi', 1], ['lo', 0]]) {
      mj.mj_resetData(m, d);
      for (let a = 0; a < m.nu; a++) {
        d.ctrl[a] = m.actuator_ctrllimited[a] ? m.actuator_ctrlrange[2 * a + side] : (side ? 1 : -1);
      }
      mj.mj_forward(m, d);
      for (const [j, vals] of Object.entries(perJoint(d.qfrc_actuator, 'v'))) {
        put('probe', `${label}/${j}`, 'qfrc_actuator', vals);
      }
      for (let a = 0; a < m.nu; a++) {
        put('probe', `${label}/${actKeys[a]}`, 'actuator_force', [d.actuator_force[a]]);
      }
      // Activations after probe_act_steps steps of the top control: the activation dynamics
      // (filters, integrators, their ranges) alone, whatever the bodies do meanwhile.
      if (side === 1 && m.na > 0) {
        for (let s = 0; s < opts.probe_act_steps; s++) mj.mj_step(m, d);
        for (let a = 0; a < m.nu; a++) {
          if (m.actuator_actnum[a] > 0) {
            put('probe', `${label}/${actKeys[a]}`, 'act', [d.act[m.actuator_actadr[a]]]);
          }
        }
      }
    }
  }

  // Models marked `extended` (the bridge corpus): the passive forces at qpos0 (gravity
  // compensation, springs) and every named sensor along both trajectories.
  const sensorKeys = [];
  if (opts.extended) {
    mj.mj_resetData(m, d);
    mj.mj_forward(m, d);
    for (const [j, vals] of Object.entries(perJoint(d.qfrc_passive, 'v'))) {
      put('passive', j, 'qfrc_passive', vals);
    }
    // 3.x routes the gravity compensation of actuatorgravcomp joints to qfrc_actuator: the sum
    // is what moves the joint.
    const total = d.qfrc_passive.map((x, i) => x + d.qfrc_actuator[i]);
    for (const [j, vals] of Object.entries(perJoint(total, 'v'))) {
      put('passive', j, 'qfrc_passive_plus_actuator', vals);
    }
    for (let i = 0; i < m.nsensor; i++) sensorKeys.push(name('mjOBJ_SENSOR', i) || `sensor#${i}`);
  }
  const sensors = (cat, s) => {
    for (let i = 0; i < sensorKeys.length; i++) {
      const adr = m.sensor_adr[i];
      put(`${cat}_sensor`, `${sensorKeys[i]}@${s}`, 'value',
          Array.from(d.sensordata.subarray(adr, adr + m.sensor_dim[i])));
    }
  };

  // Zero-control trajectories from the reset state (qpos0): without contacts (everything but
  // collision detection and contact forces), then the full physics.
  const flags = m.opt.disableflags;
  for (const [cat, off] of [['trajectory', mj.mjtDisableBit.mjDSBL_CONTACT.value],
    ['contact_trajectory', 0]]) {
    m.opt.disableflags = flags | off;
    mj.mj_resetData(m, d);
    mj.mj_forward(m, d);
    for (let s = 1; s <= opts.steps; s++) {
      mj.mj_step(m, d);
      if (s % opts.record_every === 0 || s === opts.steps) {
        for (const [j, vals] of Object.entries(perJoint(d.qpos, 'q'))) {
          put(cat, `${j}@${s}`, 'qpos', vals);
        }
        for (const [j, vals] of Object.entries(perJoint(d.qvel, 'v'))) {
          put(cat, `${j}@${s}`, 'qvel', vals);
        }
        sensors(cat, s);
      }
    }
    put(cat, 'final', 'time', [d.time]);
  }
  m.opt.disableflags = flags;
  return out;
}

const result = {version: mj.mj_versionString(), models: {}};
let index = 0;
for (const model of job.models) {
  const root = `/models/${index++}`;
  printed.length = 0;
  let m = null;
  let d = null;
  try {
    copyTree(path.dirname(model.file), root);
    try {
      m = mj.MjModel.loadFromXML(`${root}/${path.basename(model.file)}`);
    } catch (e) {
      throw new Error(exceptionText(e));
    }
    if (!m) throw new Error(printed.join(' ') || 'MjModel.loadFromXML failed');
    // Disable flags set on the compiled reference model (e.g. NATIVECCD: convex collisions
    // through libccd, as 2.2.2 does them).
    for (const flag of job.disable || []) m.opt.disableflags |= mj.mjtDisableBit[`mjDSBL_${flag}`].value;
    // A diagnosis, not a reference: "weld_diag_as_222" gives the welded bodies' rotational
    // inverse weight their translational one, which is what MuJoCo 2.2.2's efc_diagApprox uses
    // for all six rows of a weld (fixed in 3.0.0). Only meaningful for a model whose welded
    // bodies have no other constraint rows (body_invweight0 serves contacts too).
    if (model.weld_diag_as_222) {
      const w = m.body_invweight0;
      for (let i = 0; i < m.neq; i++) {
        if (m.eq_type[i] !== mj.mjtEq.mjEQ_WELD.value) continue;
        for (const obj of [m.eq_obj1id[i], m.eq_obj2id[i]]) {
          const b = m.eq_objtype[i] === OBJ.mjOBJ_SITE ? m.site_bodyid[obj] : obj;
          w[2 * b + 1] = w[2 * b];
        }
      }
    }
    d = new mj.MjData(m);
    result.models[model.id] = {data: dump(m, d, {...job, extended: !!model.extended})};
  } catch (e) {
    result.models[model.id] = {error: String(e && e.message ? e.message : e)};
  } finally {
    d?.delete();
    m?.delete();
  }
}
heapModel.delete();
process.stdout.write(JSON.stringify(result));
