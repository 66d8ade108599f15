/*---------------------------------------------------------------------------*\
  foamsilo: granular silo discharge with OpenFOAM
-------------------------------------------------------------------------------
License
    This file is part of foamsilo, built against OpenFOAM (GPL-3.0-or-later).
    It is distributed under the GNU General Public License v3 or later.

\*---------------------------------------------------------------------------*/

#include "muIRegularised.H"
#include "addToRunTimeSelectionTable.H"

// * * * * * * * * * * * * * * Static Data Members * * * * * * * * * * * * * //

namespace Foam
{
namespace viscosityModels
{
    defineTypeNameAndDebug(muIRegularised, 0);

    addToRunTimeSelectionTable
    (
        viscosityModel,
        muIRegularised,
        dictionary
    );
}
}


// * * * * * * * * * * * * Private Member Functions  * * * * * * * * * * * * //

Foam::scalar Foam::viscosityModels::muIRegularised::upperLaw
(
    const scalar I
) const
{
    const scalar ms = mus().value();
    const scalar i0 = I0().value();
    return
        (ms*i0 + (ms + deltaMu().value())*I + muInf_.value()*I*I)/(i0 + I);
}


Foam::scalar Foam::viscosityModels::muIRegularised::wellPosedness
(
    const scalar I
) const
{
    // nu = I mu'/mu from a central difference in ln I: the law is smooth
    const scalar h = 1e-4;
    const scalar mu = upperLaw(I);
    const scalar nu =
        (upperLaw(I*(1 + h)) - upperLaw(I*(1 - h)))/(2*h)/mu;
    return 4*nu*nu - 4*nu + mu*mu*sqr(1 - nu/2);
}


void Foam::viscosityModels::muIRegularised::readCoeffs()
{
    coeffs().readEntry("muInf", muInf_);
    coeffs().readEntry("alpha", alpha_);

    if
    (
        muInf_.value() < 0 || alpha_.value() <= 0 || alpha_.value() >= 2
    )
    {
        FatalIOErrorInFunction(coeffs())
            << "muIRegularised coefficients out of range: need muInf >= 0"
            << " and 0 < alpha < 2 (the low-I curve is ill-posed above 2);"
            << " got muInf " << muInf_.value()
            << ", alpha " << alpha_.value()
            << exit(FatalIOError);
    }

    // The smallest well-posed I of the law: scan up in ln I, then bisect
    const scalar Ilow = 1e-12;
    const scalar Ihigh = 1e3;
    const label nScan = 1500;
    scalar a = Ilow;
    scalar b = -1;
    for (label i = 1; i <= nScan; ++i)
    {
        const scalar I = Ilow*pow(Ihigh/Ilow, scalar(i)/nScan);
        if (wellPosedness(I) < 0)
        {
            b = I;
            break;
        }
        a = I;
    }
    if (b < 0)
    {
        FatalIOErrorInFunction(coeffs())
            << "the mu(I) law with mus " << mus().value()
            << ", deltaMu " << deltaMu().value() << ", I0 " << I0().value()
            << ", muInf " << muInf_.value()
            << " is ill-posed at every I in [" << Ilow << ", " << Ihigh
            << "]: there is no well-posed law to regularise"
            << exit(FatalIOError);
    }
    for (label i = 0; i < 200 && b - a > 1e-12*b; ++i)
    {
        const scalar m = 0.5*(a + b);
        if (wellPosedness(m) < 0)
        {
            b = m;
        }
        else
        {
            a = m;
        }
    }
    I1_ = b;
    const scalar mu1 = upperLaw(I1_);
    A_ = I1_*exp(alpha_.value()/sqr(mu1));

    // The curve below I1 must itself be well posed up to mu(I1): with
    // nu = mu^2/(2 alpha) its C is mu^2 [mu^2/alpha^2 - 2/alpha
    // + (1 - mu^2/(4 alpha))^2]
    for (label i = 1; i <= 100; ++i)
    {
        const scalar m2 = sqr(mu1*i/100);
        const scalar al = alpha_.value();
        if (sqr(m2/al) - 2*m2/al + m2*sqr(1 - m2/(4*al)) >= 0)
        {
            FatalIOErrorInFunction(coeffs())
                << "alpha " << al << " makes the low-I curve ill-posed"
                << " below mu(I1) = " << mu1 << " (I1 = " << I1_
                << "): take a smaller alpha"
                << exit(FatalIOError);
        }
    }

    Info<< "muIRegularised: well posed above I1 = " << I1_
        << " (mu = " << mu1 << "), A = " << A_ << endl;
}


Foam::tmp<Foam::volScalarField>
Foam::viscosityModels::muIRegularised::friction(const volScalarField& I) const
{
    const dimensionedScalar I1("I1", dimless, I1_);
    const volScalarField Ipos(max(I, dimensionedScalar("ISmall", dimless, VSMALL)));

    // Each branch finite everywhere: the low one is mu(I1) above I1
    const volScalarField low
    (
        sqrt(alpha_/log(dimensionedScalar("A", dimless, A_)/min(Ipos, I1)))
    );
    const volScalarField high
    (
        (mus()*I0() + (mus() + deltaMu())*Ipos + muInf_*sqr(Ipos))
       /(I0() + Ipos)
    );

    return pos0(Ipos - I1)*high + neg(Ipos - I1)*low;
}


// * * * * * * * * * * * * * * * * Constructors  * * * * * * * * * * * * * * //

Foam::viscosityModels::muIRegularised::muIRegularised
(
    const word& name,
    const dictionary& viscosityProperties,
    const volVectorField& U,
    const surfaceScalarField& phi
)
:
    muI(name, viscosityProperties, U, phi, typeName + "Coeffs"),
    muInf_("muInf", dimless, Zero),
    alpha_("alpha", dimless, Zero),
    I1_(0),
    A_(0)
{
    readCoeffs();
    update();
}


// * * * * * * * * * * * * * * Member Functions  * * * * * * * * * * * * * * //

bool Foam::viscosityModels::muIRegularised::read
(
    const dictionary& viscosityProperties
)
{
    muI::read(viscosityProperties);
    readCoeffs();
    update();

    return true;
}


// ************************************************************************* //
