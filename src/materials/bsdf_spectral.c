/* bsdf_at_wavelengths (bsdf_spectral.h): the one place a BSDF's colours become spectral
 * values; scene_bsdf calls it after building the BSDF in RGB. */
#include "materials/bsdf_spectral.h"

void bsdf_at_wavelengths(Bsdf *b, const Wavelengths *wl)
{
    switch (b->type) {
    case MATERIAL_DIFFUSE:
    case MATERIAL_MIRROR: b->lobe.diffuse.albedo = spectrum_albedo(b->lobe.diffuse.albedo, wl); break;
    case MATERIAL_GLASS:
    case MATERIAL_DIELECTRIC: b->lobe.dielectric.tint = spectrum_albedo(b->lobe.dielectric.tint, wl); break;
    case MATERIAL_CONDUCTOR:
        b->lobe.conductor.eta = spectrum_unbounded(b->lobe.conductor.eta, wl);
        b->lobe.conductor.k = spectrum_unbounded(b->lobe.conductor.k, wl);
        break;
    case MATERIAL_PLASTIC: b->lobe.plastic.albedo = spectrum_albedo(b->lobe.plastic.albedo, wl); break;
    case MATERIAL_THIN_DIELECTRIC: b->lobe.dielectric.tint = spectrum_albedo(b->lobe.dielectric.tint, wl); break;
    case MATERIAL_DIFFUSE_TRANSMISSION:
        b->lobe.difftrans.reflectance = spectrum_albedo(b->lobe.difftrans.reflectance, wl);
        b->lobe.difftrans.transmittance = spectrum_albedo(b->lobe.difftrans.transmittance, wl);
        break;
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR:
        /* The conductor base's eta and k arrive divided by the layer's (scalar) eta: the
         * upsampled ratio is the ratio of the upsampled values, the scalar commuting. */
        b->lobe.layered.reflectance = spectrum_albedo(b->lobe.layered.reflectance, wl);
        b->lobe.layered.eta = spectrum_unbounded(b->lobe.layered.eta, wl);
        b->lobe.layered.k = spectrum_unbounded(b->lobe.layered.k, wl);
        b->lobe.layered.albedo = spectrum_albedo(b->lobe.layered.albedo, wl);
        break;
    case MATERIAL_MEASURED: /* its tables are evaluated at the wavelengths themselves */
        b->lobe.measured.spectral = true;
        for (int i = 0; i < COLOR_LANES; i++) b->lobe.measured.lambda[i] = wl->lambda[i];
        break;
    case MATERIAL_HAIR: { /* sigma_a per wavelength, as pbrt-v4's HairMaterial */
        HairLobe *h = &b->lobe.hair;
        h->sigma_a = h->from_color ? hair_sigma_a_from_color(spectrum_albedo(h->source, wl), h->beta_n)
                                   : spectrum_unbounded(h->source, wl);
        break;
    }
    case MATERIAL_MIX: break; /* never a Bsdf's type: scene_bsdf resolves a mix first */
    }
}

MaterialSpectra material_spectra(const Material *m)
{
    MaterialSpectra ms = {spectrum_rgb_albedo(m->albedo), spectrum_rgb_unbounded(m->eta), spectrum_rgb_unbounded(m->k)};
    return ms;
}

void bsdf_at_wavelengths_prepared(Bsdf *b, const MaterialSpectra *ms, const Wavelengths *wl)
{
    switch (b->type) {
    case MATERIAL_DIFFUSE:
    case MATERIAL_MIRROR: b->lobe.diffuse.albedo = spectrum_rgb_eval(&ms->albedo, wl); break;
    case MATERIAL_GLASS:
    case MATERIAL_DIELECTRIC: b->lobe.dielectric.tint = spectrum_rgb_eval(&ms->albedo, wl); break;
    case MATERIAL_CONDUCTOR:
        b->lobe.conductor.eta = spectrum_rgb_eval(&ms->eta, wl);
        b->lobe.conductor.k = spectrum_rgb_eval(&ms->k, wl);
        break;
    case MATERIAL_PLASTIC: b->lobe.plastic.albedo = spectrum_rgb_eval(&ms->albedo, wl); break;
    default: bsdf_at_wavelengths(b, wl); break; /* types without a prepared form */
    }
}
