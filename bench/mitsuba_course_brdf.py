"""mitsuba_course_brdf.py — the course's hw6 BRDFs as a Mitsuba 3 BSDF plugin ("coursebrdf"), so that the
path benchmark (bench_mitsuba_path.py, through to_mitsuba_path.py) renders glossy course materials in
Mitsuba as clrt does. Mitsuba 3 has no Phong or Blinn-Phong plugin, and its microfacet models have
another shape and Fresnel than the course's Torrance-Sparrow.

The formulas are clrt's (cl_kernels/brdf.cl, the comment at its top; host reference
tests/brdf_reference.h), written again here in Dr.Jit (f: the BRDF, θi, θo the angles of the light and
viewing directions to n, αr between the viewing direction and the light direction mirrored about n, αh
between n and the half vector):
  original_phong        kd + ks cos^p αr / cosθi
  original_blinn_phong  kd + ks cos^p αh / cosθi   (also a classic material: p = PhongExponent)
  modified_phong        kd + ks cos^p αr;   normalized: kd/π + ks (p+2)/(2π) cos^p αr
  modified_blinn_phong  kd + ks cos^p αh;   normalized: kd/π + ks (p+8)/(8π) cos^p αh
  torrance_sparrow      (1−F if kd_fresnel) kd/π + ks D F G / (4 cosθi cosθo), D = (p+2)/(2π) cos^p αh,
                        G = min(1, 2 cosαh cosθo / (wo·h), 2 cosαh cosθi / (wo·h)), F the course's
                        conductor Fresnel of (eta, k) at θi
f = 0 unless both directions are above the surface (wrap it in "twosided" for clrt's two-sided opaque
materials). Sampling (Mitsuba's own noise only; the pdf matches it, so the image's expectation does not
depend on it): clrt's mixture, a cosine lobe with probability 1 − s and the glossy lobe with s =
mean(ks) / (mean(kd) + mean(ks)); Phong lobes about the mirrored direction with density (p+1)/(2π) cos^p,
Blinn-Phong half vectors about n with (p+1)/(2π) cos^p αh, Torrance-Sparrow's with (p+2)/(2π) cos^(p+1) αh.

Properties: kind (one of the names above), exponent, normalized (bool), kd_r/g/b, ks_r/g/b, eta, k,
kd_fresnel (bool); kd_tex, ks_tex (textures: kd and ks per point, replacing the constants; the lobe
choice s keeps the constants'). register() adds the plugin; call it after mitsuba.set_variant (a JIT variant:
llvm_ad_rgb, as the benchmark uses).
"""
import math

KINDS = ("original_phong", "original_blinn_phong", "modified_phong", "modified_blinn_phong", "torrance_sparrow")


def register():
    import drjit as dr
    import mitsuba as mi

    inv_pi = 1.0 / math.pi

    def mirrored(w):  # w mirrored about n = (0, 0, 1)
        return mi.Vector3f(-w.x, -w.y, w.z)

    def half_cos(wi, wo):  # cos αh, and wo·h, for h = normalize(wi + wo)
        h = dr.normalize(wi + wo)
        return dr.maximum(h.z, 0.0), dr.dot(wo, h), h

    class CourseBrdf(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.kind = props.get("kind", "modified_phong")
            if self.kind not in KINDS:
                raise ValueError("coursebrdf: unknown kind '%s'" % self.kind)
            self.p = float(props.get("exponent", 1.0))
            self.normalized = bool(props.get("normalized", False))
            self.kd = mi.Color3f(*[float(props.get("kd_" + c, 0.0)) for c in "rgb"])
            self.ks = mi.Color3f(*[float(props.get("ks_" + c, 0.0)) for c in "rgb"])
            self.eta, self.k = float(props.get("eta", 1.0)), float(props.get("k", 0.0))
            self.kd_fresnel = bool(props.get("kd_fresnel", False))
            self.kd_tex = props.get("kd_tex", None)
            self.ks_tex = props.get("ks_tex", None)
            mkd = sum(float(props.get("kd_" + c, 0.0)) for c in "rgb") / 3.0
            mks = sum(float(props.get("ks_" + c, 0.0)) for c in "rgb") / 3.0
            self.s = mks / (mkd + mks) if mkd + mks > 0.0 else 0.0
            flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def fresnel(self, cos_i):
            n, k = self.eta, self.k
            c2, nk = cos_i * cos_i, n * n + k * k
            rs = (nk - 2.0 * n * cos_i + c2) / (nk + 2.0 * n * cos_i + c2)
            rp = (nk * c2 - 2.0 * n * cos_i + 1.0) / (nk * c2 + 2.0 * n * cos_i + 1.0)
            return 0.5 * (rs + rp)

        def colours(self, si, active):
            kd = self.kd_tex.eval(si, active) if self.kd_tex is not None else self.kd
            ks = self.ks_tex.eval(si, active) if self.ks_tex is not None else self.ks
            return kd, ks

        def f(self, wo, wi, kd, ks):
            """clrt's f(wo: towards the viewer, wi: towards the light), both local; 0 below the surface."""
            cos_o, cos_i = wo.z, wi.z
            above = (cos_i > 0.0) & (cos_o > 0.0)
            p = self.p
            cos_r = dr.maximum(dr.dot(mirrored(wi), wo), 0.0)
            cos_h, wo_h, _ = half_cos(wi, wo)
            if self.kind == "original_phong":
                val = kd + ks * (dr.power(cos_r, p) / cos_i)
            elif self.kind == "original_blinn_phong":
                val = kd + ks * (dr.power(cos_h, p) / cos_i)
            elif self.kind == "modified_phong":
                val = (kd * inv_pi + ks * (dr.power(cos_r, p) * (p + 2.0) * 0.5 * inv_pi)) if self.normalized \
                    else kd + ks * dr.power(cos_r, p)
            elif self.kind == "modified_blinn_phong":
                val = (kd * inv_pi + ks * (dr.power(cos_h, p) * (p + 8.0) * 0.125 * inv_pi)) if self.normalized \
                    else kd + ks * dr.power(cos_h, p)
            else:
                d = (p + 2.0) * 0.5 * inv_pi * dr.power(cos_h, p)
                g = dr.minimum(1.0, dr.minimum(2.0 * cos_h * cos_o / wo_h, 2.0 * cos_h * cos_i / wo_h))
                fr = self.fresnel(cos_i)
                kd_eff = (1.0 - fr) * kd if self.kd_fresnel else kd
                val = kd_eff * inv_pi + ks * (d * fr * g / (4.0 * cos_i * cos_o))
            return dr.select(above, val, 0.0)

        def lobe_pdf(self, wo, wi):
            """The mixture's density of wi (solid angle) given wo."""
            p = self.p
            cos_pdf = dr.maximum(wi.z, 0.0) * inv_pi
            if self.kind in ("original_phong", "modified_phong"):
                c = dr.maximum(dr.dot(mirrored(wo), wi), 0.0)
                glossy = (p + 1.0) * 0.5 * inv_pi * dr.power(c, p)
            else:
                cos_h, wo_h, _ = half_cos(wi, wo)
                e = p + 1.0 if self.kind == "torrance_sparrow" else p
                ph = (e + 1.0) * 0.5 * inv_pi * dr.power(cos_h, e)
                glossy = dr.select(dr.abs(wo_h) > 0.0, ph / (4.0 * dr.abs(wo_h)), 0.0)
            return (1.0 - self.s) * cos_pdf + self.s * glossy

        def sample(self, ctx, si, sample1, sample2, active=True):
            wo = si.wi  # clrt's wo: towards the viewer
            glossy = sample1 < self.s
            wi_cos = mi.warp.square_to_cosine_hemisphere(sample2)
            e = self.p + (1.0 if self.kind == "torrance_sparrow" else 0.0)
            cos_a = dr.power(sample2.x, 1.0 / (e + 1.0))
            sin_a = dr.safe_sqrt(1.0 - cos_a * cos_a)
            sp, cp = dr.sincos(2.0 * math.pi * sample2.y)
            local = mi.Vector3f(sin_a * cp, sin_a * sp, cos_a)
            if self.kind in ("original_phong", "modified_phong"):
                wi_gl = mi.Frame3f(mirrored(wo)).to_world(local)
            else:
                h = local  # about n
                wi_gl = 2.0 * dr.dot(wo, h) * h - wo
            wi = dr.select(glossy, wi_gl, wi_cos)
            bs = mi.BSDFSample3f()
            bs.wo = wi
            bs.pdf = self.lobe_pdf(wo, wi)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            ok = active & (wo.z > 0.0) & (wi.z > 0.0) & (bs.pdf > 0.0)
            kd, ks = self.colours(si, active)
            value = self.f(wo, wi, kd, ks) * wi.z / bs.pdf
            return bs, dr.select(ok, value, 0.0)

        def eval(self, ctx, si, wo, active=True):  # Mitsuba's wo: towards the light (clrt's wi)
            kd, ks = self.colours(si, active)
            return dr.select(active, self.f(si.wi, wo, kd, ks) * dr.maximum(wo.z, 0.0), 0.0)

        def pdf(self, ctx, si, wo, active=True):
            return dr.select(active & (si.wi.z > 0.0) & (wo.z > 0.0), self.lobe_pdf(si.wi, wo), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def traverse(self, callback):
            if self.kd_tex is not None:
                callback.put("kd_tex", self.kd_tex, mi.ParamFlags.NonDifferentiable)
            if self.ks_tex is not None:
                callback.put("ks_tex", self.ks_tex, mi.ParamFlags.NonDifferentiable)

        def to_string(self):
            return "CourseBrdf[kind=%s, exponent=%g, normalized=%s]" % (self.kind, self.p, self.normalized)

    mi.register_bsdf("coursebrdf", lambda props: CourseBrdf(props))
